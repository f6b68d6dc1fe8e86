# Installs the library, headers, an exported CMake package usable as
#   find_package(combabc) ; target_link_libraries(app PRIVATE combabc::combabc)
#   find_package(combabc COMPONENTS engine) ; target_link_libraries(app PRIVATE combabc::engine)
# a pkg-config file, the CLI with its report script, man page and bash completion, and the Python
# module; and packages all of it as a .deb (cpack -G DEB). The installed tree is relocatable:
# nothing in it names the prefix (cmake/CombabcLayout.cmake).
include(CMakePackageConfigHelpers)

# One export file per component (combabc_<name>Targets.cmake), so that the package config loads,
# and finds the dependencies of, only the components asked for; combabcTargets.cmake holds
# combabc::combabc, all of them.
set(COMBABC_COMPONENT_NAMES "")
foreach(target ${COMBABC_COMPONENTS})
  string(REGEX REPLACE "^combabc_" "" name ${target})
  list(APPEND COMBABC_COMPONENT_NAMES ${name})
  install(TARGETS ${target} EXPORT ${target}Targets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(EXPORT ${target}Targets NAMESPACE combabc:: FILE ${target}Targets.cmake
    DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/combabc)
endforeach()
install(TARGETS combabc EXPORT combabcTargets)
install(DIRECTORY include/combabc DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT combabcTargets NAMESPACE combabc:: FILE combabcTargets.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/combabc)
configure_package_config_file(cmake/combabcConfig.cmake.in
  ${PROJECT_BINARY_DIR}/combabcConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/combabc)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/combabcConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/combabcConfig.cmake ${PROJECT_BINARY_DIR}/combabcConfigVersion.cmake
  cmake/FindLibCsv.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/combabc)

# pkg-config: a static library needs its private dependencies on the link line too.
if(COMBABC_SHARED)
  set(COMBABC_PC_RPATH "-Wl,-rpath,\${libdir} ")
  set(COMBABC_PC_STATIC_LIBS "")
else()
  set(COMBABC_PC_RPATH "")
  set(COMBABC_PC_STATIC_LIBS "-lsqlite3 -ltomlplusplus -lcsv")
  foreach(lib ${CMAKE_DL_LIBS})
    string(APPEND COMBABC_PC_STATIC_LIBS " -l${lib}")
  endforeach()
endif()
configure_file(cmake/combabc.pc.in ${PROJECT_BINARY_DIR}/combabc.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/combabc.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

if(COMBABC_BUILD_APPS)
  install(TARGETS combabc_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY scripts/report DESTINATION ${CMAKE_INSTALL_DATADIR}/combabc
    PATTERN __pycache__ EXCLUDE)
  install(FILES docs/man/combabc.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
  install(FILES scripts/completion/combabc.bash RENAME combabc
    DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions)
endif()

# The .deb: `cpack -G DEB` in the build directory writes combabc_<version>_<arch>.deb, installing
# under /usr. Depends: the shared libraries' packages (dpkg-shlibdeps, from dpkg-dev) and the
# report's python3 + numpy + matplotlib; what a program built against the headers needs is
# recommended.
set(CPACK_PACKAGE_NAME combabc)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_CONTACT "combabc developers <combabc@localhost>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "python3, python3-numpy, python3-matplotlib")
if(COMBABC_HAVE_PYTHON)  # the module is built for one Python minor version
  set(py ${Python3_VERSION_MAJOR}.${Python3_VERSION_MINOR})
  math(EXPR next "${Python3_VERSION_MINOR} + 1")
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS
    ", python3 (>= ${py}~), python3 (<< ${Python3_VERSION_MAJOR}.${next})")
endif()
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS
  "python3-pandas, python3-xarray, python3-netcdf4, libeigen3-dev, libsqlite3-dev, libtomlplusplus-dev, libcsv-dev, pkg-config, bash-completion")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "openmpi-bin")
set(CPACK_GENERATOR DEB)
include(CPack)
