# Debian packages with CPack (`cpack -G DEB` in a build folder, after the build):
#   lasercell          the CLI (component cli); its shared-library dependencies come from
#                      dpkg-shlibdeps, as for any Debian binary.
#   liblasercell-dev   headers, the static module libraries and the CMake package (component
#                      dev); it depends on the Debian -dev packages that find_package(lasercell)
#                      looks for (cmake/lasercellConfig.cmake.in).
#   python3-lasercell  the Python module (component python), when LASERCELL_BUILD_PYTHON.
# tests/install/check_install.cmake (MODE=deb) builds both and unpacks them into a scratch root.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME lasercell)
set(CPACK_PACKAGE_VENDOR "lasercell")
set(CPACK_PACKAGE_CONTACT "lasercell maintainers <lasercell@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "Laser-triangulation metrology cell toolkit: calibration, sweeps, part localization")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL cli dev)
if(LASERCELL_BUILD_PYTHON)
  list(APPEND CPACK_COMPONENTS_ALL python)
endif()
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# gzip: xz takes minutes on the static libraries for a few percent less size.
set(CPACK_DEBIAN_COMPRESSION_TYPE gzip)

set(CPACK_DEBIAN_CLI_PACKAGE_NAME lasercell)
set(CPACK_DEBIAN_CLI_PACKAGE_SHLIBDEPS ON)
set(CPACK_COMPONENT_CLI_DESCRIPTION
    "lasercell command line: calibrate a laser cell, triangulate sweeps, localize parts")

set(CPACK_DEBIAN_DEV_PACKAGE_NAME liblasercell-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
string(JOIN ", " CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
  cmake pkg-config libeigen3-dev libyaml-cpp-dev nlohmann-json3-dev libtbb-dev libnanoflann-dev
  libceres-dev libmrcal-dev libopencv-dev libopencv-contrib-dev libembree-dev libaravis-dev
  libocct-data-exchange-dev libocct-modeling-algorithms-dev libocct-modeling-data-dev
  libocct-foundation-dev)
set(CPACK_COMPONENT_DEV_DESCRIPTION
    "lasercell C++ libraries (static), headers and CMake package: find_package(lasercell)")

set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-lasercell)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS "python3 (>= 3.9), python3-numpy")
set(CPACK_COMPONENT_PYTHON_DESCRIPTION
    "lasercell for Python (import lasercell): clouds, cells, cameras, sweeps, calibrations, PPF localization and jobs, with NumPy arrays")

include(CPack)
