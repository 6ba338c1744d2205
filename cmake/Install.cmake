# `cmake --install <build> --prefix <dir>`: the lasercell CLI, the module libraries (static), their
# headers under include/lasercell/<module>/, and a CMake package, so that another project writes
#   find_package(lasercell 0.1 REQUIRED)
#   target_link_libraries(app PRIVATE lasercell::registration)
# and includes "registration/normals.hpp" as lasercell's own sources do. tests/install builds
# such a project against an installed tree.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(LASERCELL_MODULES core calib triangulation registration localize datasets)
set(LASERCELL_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/lasercell)

foreach(module IN LISTS LASERCELL_MODULES)
  set_target_properties(lasercell_${module} PROPERTIES EXPORT_NAME ${module})
  # Headers keep their folder below the module (core/io, registration/internal ...): the
  # public headers include those. install(DIRECTORY) would also create the data folders empty.
  file(GLOB_RECURSE headers RELATIVE ${PROJECT_SOURCE_DIR} CONFIGURE_DEPENDS
       ${PROJECT_SOURCE_DIR}/${module}/*.hpp)
  # Not the API: <module>/internal/ and core/io's codec pieces (no public header includes them).
  list(FILTER headers EXCLUDE REGEX "/internal/|^core/io/(codec|ply_header|lzf)\\.hpp$")
  foreach(header IN LISTS headers)
    get_filename_component(folder ${header} DIRECTORY)
    install(FILES ${PROJECT_SOURCE_DIR}/${header}
            DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/lasercell/${folder} COMPONENT dev)
  endforeach()
  list(APPEND LASERCELL_LIBRARY_TARGETS lasercell_${module})
endforeach()

install(TARGETS ${LASERCELL_LIBRARY_TARGETS} EXPORT lasercellTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
install(TARGETS lasercell RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT cli)
install(EXPORT lasercellTargets NAMESPACE lasercell:: DESTINATION ${LASERCELL_CMAKE_DIR}
        COMPONENT dev)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/lasercellConfig.cmake.in
  ${PROJECT_BINARY_DIR}/lasercellConfig.cmake INSTALL_DESTINATION ${LASERCELL_CMAKE_DIR})
# 0.x: a new minor version may change the API, so only the same minor version is compatible.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/lasercellConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/lasercellConfig.cmake
              ${PROJECT_BINARY_DIR}/lasercellConfigVersion.cmake
        DESTINATION ${LASERCELL_CMAKE_DIR} COMPONENT dev)
