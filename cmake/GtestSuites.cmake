# One ctest test per GoogleTest suite (`<module>.<Suite>`, running `--gtest_filter=Suite.*`),
# instead of one process per test: suites share expensive fixtures (SetUpTestSuite, function
# statics such as a simulated data set or rendered images), which a process per test would
# rebuild for every test of the suite.
#
# Suites are read from the sources at configure time (TEST/TEST_F/TEST_P lines).
# `<module>.all_suites_registered` fails when the binary holds a suite that was not registered
# (e.g. a macro spelled in a way the scan misses), so no test can be skipped silently.

function(lasercell_add_gtest_suites target module)
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES" ${ARGN})
  set(suites "")
  foreach(src IN LISTS ARG_SOURCES)
    file(STRINGS "${src}" lines REGEX "^[ \t]*(TYPED_)?TEST(_F|_P)?\\([ \t]*[A-Za-z0-9_]+")
    foreach(line IN LISTS lines)
      string(REGEX REPLACE "^[ \t]*(TYPED_)?TEST(_F|_P)?\\([ \t]*([A-Za-z0-9_]+).*" "\\3" suite
                           "${line}")
      list(APPEND suites "${suite}")
    endforeach()
  endforeach()
  list(REMOVE_DUPLICATES suites)
  list(SORT suites)
  foreach(suite IN LISTS suites)
    # `Prefix/Suite.Name/N` are the instances of a parameterized suite.
    add_test(NAME ${module}.${suite}
             COMMAND ${target} --gtest_filter=${suite}.*:*/${suite}.* --gtest_brief=1)
    set_tests_properties(${module}.${suite} PROPERTIES TIMEOUT ${ARG_TIMEOUT})
    if(LASERCELL_SANITIZE)
      set_tests_properties(${module}.${suite} PROPERTIES ENVIRONMENT
                           "LSAN_OPTIONS=suppressions=${PROJECT_SOURCE_DIR}/tests/lsan.supp")
    endif()
  endforeach()
  string(REPLACE ";" "," suite_csv "${suites}")
  add_test(NAME ${module}.all_suites_registered
           COMMAND ${CMAKE_COMMAND} -DBINARY=$<TARGET_FILE:${target}> -DSUITES=${suite_csv}
                   -P ${PROJECT_SOURCE_DIR}/cmake/CheckGtestSuites.cmake)
endfunction()
