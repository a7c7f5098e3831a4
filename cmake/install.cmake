# What `cmake --install` puts where, so another project finds ctk with find_package(ctk) and links
# ctk::core, ctk::geom, ctk::measure, ctk::proj, ctk::recon, ctk::calib, ctk::phantoms, ctk::plan and
# ctk::plan_simulated; and the Debian package CPack makes of it (`cpack -G DEB` in the build tree).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(ctk_libraries ctk_core ctk_geom ctk_measure ctk_proj ctk_recon ctk_calib ctk_phantoms ctk_plan ctk_plan_simulated)
foreach(library IN LISTS ctk_libraries)
  string(REGEX REPLACE "^ctk_" "" name ${library})
  set_target_properties(${library} PROPERTIES EXPORT_NAME ${name})
endforeach()
install(TARGETS ${ctk_libraries} EXPORT ctkTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
foreach(folder libcore libgeom libmeasure libproj librecon libcalib libplan phantoms)
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/${folder}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endforeach()
set(ctk_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/ctk)
install(EXPORT ctkTargets NAMESPACE ctk:: DESTINATION ${ctk_cmake_dir})
configure_package_config_file(${CMAKE_SOURCE_DIR}/cmake/ctkConfig.cmake.in ${CMAKE_BINARY_DIR}/ctkConfig.cmake
                              INSTALL_DESTINATION ${ctk_cmake_dir})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/ctkConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/ctkConfig.cmake ${CMAKE_BINARY_DIR}/ctkConfigVersion.cmake
              ${CMAKE_SOURCE_DIR}/cmake/opencv_modules.cmake DESTINATION ${ctk_cmake_dir})

# The Debian package: everything installed, the run-time libraries it needs found by dpkg-shlibdeps.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME ctk)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "Calibrate and reconstruct cone-beam CT scans along arbitrary (robot) trajectories")
set(CPACK_PACKAGE_CONTACT "ctk developers <ctk@localhost>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
include(CPack)
