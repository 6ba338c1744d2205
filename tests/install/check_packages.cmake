# Part of check_install.cmake (MODE=deb): builds lasercell's Debian packages with CPack from
# BUILD_DIR (python3-lasercell too when -DPYTHON=<interpreter> is given), checks their names
# and dependencies, unpacks them into ${WORK_DIR}/root and sets `prefix` to the unpacked /usr;
# the unpacked Python package must import and read a cloud.
run_step("cpack" ${CMAKE_COMMAND} -E chdir ${BUILD_DIR}
         ${CMAKE_CPACK_COMMAND} -G DEB -B ${WORK_DIR}/packages)
file(GLOB debs ${WORK_DIR}/packages/*.deb)
set(root ${WORK_DIR}/root)
set(names "")
foreach(deb IN LISTS debs)
  run_step("dpkg-deb --field ${deb}" dpkg-deb --field ${deb} Package Depends)
  string(REGEX MATCH "Package: ([a-z0-9.+-]+)" _ "${step_output}")
  set(name ${CMAKE_MATCH_1})
  list(APPEND names ${name})
  # The CLI's dependencies come from dpkg-shlibdeps: it must name the libraries it is linked with.
  # (Debian's Ceres is a static library; mrcal and OpenCV are shared.)
  if(name STREQUAL "lasercell" AND NOT step_output MATCHES "libmrcal[0-9]+ .*libopencv-core")
    message(FATAL_ERROR "lasercell.deb does not depend on mrcal's and OpenCV's libraries:\n"
                        "${step_output}")
  endif()
  if(name STREQUAL "liblasercell-dev" AND NOT step_output MATCHES "libceres-dev")
    message(FATAL_ERROR "liblasercell-dev.deb does not depend on libceres-dev:\n${step_output}")
  endif()
  run_step("dpkg-deb -x ${deb}" dpkg-deb -x ${deb} ${root})
endforeach()
list(SORT names)
set(expected "lasercell;liblasercell-dev")
if(PYTHON)
  list(APPEND expected python3-lasercell)
endif()
if(NOT names STREQUAL expected)
  message(FATAL_ERROR "cpack made the packages '${names}', expected '${expected}'")
endif()
set(prefix ${root}/usr)
if(NOT PYTHON)
  return()
endif()
# The unpacked Python package imports and reads a cloud, with nothing of the build tree on the path.
# (A script file: the semicolons of a one-line -c program would split CMake's argument list.)
file(WRITE ${WORK_DIR}/import_check.py "import sys\nimport lasercell\n"
     "cloud = lasercell.read_point_cloud(sys.argv[1])\nprint(lasercell.__file__, len(cloud))\n")
run_step("python3 import_check.py" ${CMAKE_COMMAND} -E env
         PYTHONPATH=${prefix}/lib/python3/dist-packages PYTHONNOUSERSITE=1
         ${PYTHON} ${WORK_DIR}/import_check.py
         ${SOURCE_DIR}/datasets/real/uwa/parasaurolophus_6700.bin.ply)
if(NOT step_output MATCHES "^${prefix}/lib/python3/dist-packages/lasercell/__init__.py 6700")
  message(FATAL_ERROR "the unpacked python3-lasercell did not import from the root: ${step_output}")
endif()
