# Installs the library, headers and an exported CMake package usable as
#   find_package(combabc) ; target_link_libraries(app PRIVATE combabc::combabc)
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS combabc ${COMBABC_COMPONENTS} EXPORT combabcTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY include/combabc DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT combabcTargets NAMESPACE combabc:: FILE combabcTargets.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/combabc)
configure_package_config_file(cmake/combabcConfig.cmake.in
  ${PROJECT_BINARY_DIR}/combabcConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/combabc)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/combabcConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/combabcConfig.cmake ${PROJECT_BINARY_DIR}/combabcConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/combabc)
if(COMBABC_BUILD_APPS)
  install(TARGETS combabc_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY scripts/report DESTINATION ${CMAKE_INSTALL_DATADIR}/combabc OPTIONAL)
endif()
