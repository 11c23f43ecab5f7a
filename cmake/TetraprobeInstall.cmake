# Installs the engine side only: the permissive runtime libraries, their headers and the GLSL includes,
# with a CMake package so engines can `find_package(tetraprobe)` and link `tetraprobe::runtime` /
# `tetraprobe::runtime_vulkan`. Nothing from the build side (CGAL, TetGen, Embree) is installed or exported.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set_target_properties(tetraprobe_runtime PROPERTIES EXPORT_NAME runtime)
set_target_properties(tetraprobe_runtime_vulkan PROPERTIES EXPORT_NAME runtime_vulkan)
set_target_properties(tetraprobe_warnings PROPERTIES EXPORT_NAME warnings)
install(TARGETS tetraprobe_runtime tetraprobe_runtime_vulkan tetraprobe_warnings
  EXPORT tetraprobeTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/runtime/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/shaders/ DESTINATION ${CMAKE_INSTALL_DATADIR}/tetraprobe/shaders
  FILES_MATCHING PATTERN "tetraprobe*.glsl")
install(EXPORT tetraprobeTargets NAMESPACE tetraprobe:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/tetraprobe)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/tetraprobeConfig.cmake.in
  ${PROJECT_BINARY_DIR}/tetraprobeConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/tetraprobe
  PATH_VARS CMAKE_INSTALL_DATADIR)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/tetraprobeConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/tetraprobeConfig.cmake ${PROJECT_BINARY_DIR}/tetraprobeConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/tetraprobe)
