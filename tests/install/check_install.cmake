# ctest `install.FindPackage` (MODE=install): installs the build tree into a scratch prefix.
# ctest `install.DebianPackages` (MODE=deb): builds the Debian packages with CPack, checks their
# metadata and unpacks them into a scratch root (dpkg-deb -x, so the machine's /usr is untouched).
# Either way it then runs the installed CLI, and configures, builds and runs
# tests/install/consumer against the installed tree only.
# cmake -DMODE=install|deb -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... [-DLAUNCHER=ccache]
#       -P check_install.cmake
foreach(var MODE BUILD_DIR SOURCE_DIR WORK_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "check_install.cmake: -D${var}=... is required")
  endif()
endforeach()

function(run_step name)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name} failed (${rc}):\n${out}\n${err}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
if(MODE STREQUAL "install")
  set(prefix ${WORK_DIR}/prefix)
  run_step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
elseif(MODE STREQUAL "deb")
  include(${CMAKE_CURRENT_LIST_DIR}/check_packages.cmake)
else()
  message(FATAL_ERROR "check_install.cmake: MODE must be install or deb, not '${MODE}'")
endif()

run_step("installed lasercell --version" ${prefix}/bin/lasercell --version)
if(NOT step_output MATCHES "^lasercell [0-9]+\\.[0-9]+\\.[0-9]+")
  message(FATAL_ERROR "installed lasercell --version printed '${step_output}'")
endif()
foreach(file lib/cmake/lasercell/lasercellConfig.cmake include/lasercell/core/point_cloud.hpp
             include/lasercell/core/io/point_cloud_io.hpp lib/liblasercell_core.a
             lib/liblasercell_localize.a)
  if(NOT EXISTS ${prefix}/${file})
    message(FATAL_ERROR "the install tree lacks ${file}")
  endif()
endforeach()

# Only the prefix is visible to the consumer: no path into lasercell's source or build tree.
set(configure ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/install/consumer -B ${WORK_DIR}/consumer
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
if(LAUNCHER)
  list(APPEND configure -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
run_step("configuring the consumer" ${configure})
run_step("building the consumer" ${CMAKE_COMMAND} --build ${WORK_DIR}/consumer)
run_step("running the consumer" ${WORK_DIR}/consumer/consumer
         ${SOURCE_DIR}/datasets/real/uwa/parasaurolophus_6700.bin.ply
         ${SOURCE_DIR}/datasets/demo/cell.yaml)
message(STATUS "consumer printed:\n${step_output}")
foreach(line "points 6700 normals [0-9]+" "frames [1-9]" "cad refused a missing file")
  if(NOT step_output MATCHES "${line}")
    message(FATAL_ERROR "the consumer's output lacks '${line}':\n${step_output}")
  endif()
endforeach()
