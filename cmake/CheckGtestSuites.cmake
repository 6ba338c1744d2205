cmake_minimum_required(VERSION 3.16)
# ctest script: every suite that BINARY lists (--gtest_list_tests) must be among SUITES (comma
# separated), the suites lasercell_add_gtest_suites registered as ctest tests.
execute_process(COMMAND ${BINARY} --gtest_list_tests OUTPUT_VARIABLE listing
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${BINARY} --gtest_list_tests failed (${rc})")
endif()
string(REPLACE "," ";" registered "${SUITES}")
string(REPLACE "\n" ";" lines "${listing}")
set(missing "")
foreach(line IN LISTS lines)
  # Suite lines start in column 0 and end with '.'; parameterized ones read `Prefix/Suite.`.
  if(line MATCHES "^([A-Za-z0-9_]+/)?([A-Za-z0-9_]+)\\.")
    set(suite "${CMAKE_MATCH_2}")
    if(NOT suite IN_LIST registered)
      list(APPEND missing "${suite}")
    endif()
  endif()
endforeach()
if(missing)
  message(FATAL_ERROR "suites not registered with ctest (cmake/GtestSuites.cmake did not find "
                      "their TEST lines): ${missing}")
endif()
message(STATUS "all suites of ${BINARY} are registered")
