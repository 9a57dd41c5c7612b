# `cmake --install` puts libscan2lod.a, the headers it needs and a CMake
# package in place, so that another project can write
#   find_package(scan2lod REQUIRED)
#   target_link_libraries(app PRIVATE scan2lod::scan2lod)
# and load .mco models, take levels and write glTF without PCL, VTK or Open3D.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(SCAN2LOD_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/scan2lod)

install(TARGETS scan2lod_runtime EXPORT scan2lodTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
# The runtime's headers and the plain-data headers they include; lod/ and its
# rooms list theirs where their sources are (SCAN2LOD_INSTALLED_HEADERS).
get_property(lod_headers GLOBAL PROPERTY SCAN2LOD_INSTALLED_HEADERS)
foreach(header
    core/types.h core/array_view.h core/large_array.h core/progress.h core/error.h core/mesh_edges.h
    core/parallel_jobs.h core/flat_hash.h
    io/atomic_file.h io/gltf_file.h
    delivery/tileset.h delivery/tile_glb.h delivery/tile_tree.h
    ${lod_headers}
    reconstruct/marching_cubes.h reconstruct/signed_distance.h reconstruct/cube_grid.h reconstruct/cube_table.h)
  get_filename_component(folder ${header} DIRECTORY)
  install(FILES ${header} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/scan2lod/${folder})
endforeach()
install(EXPORT scan2lodTargets NAMESPACE scan2lod:: DESTINATION ${SCAN2LOD_CMAKE_DIR})

configure_package_config_file(cmake/scan2lodConfig.cmake.in ${CMAKE_BINARY_DIR}/scan2lodConfig.cmake
                              INSTALL_DESTINATION ${SCAN2LOD_CMAKE_DIR})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/scan2lodConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/scan2lodConfig.cmake ${CMAKE_BINARY_DIR}/scan2lodConfigVersion.cmake
        DESTINATION ${SCAN2LOD_CMAKE_DIR})
install(TARGETS scan2lod RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# Where scan2lod looks for it (cli/full_program.cpp): bin/../libexec/scan2lod.
install(TARGETS scan2lod-full RUNTIME DESTINATION ${CMAKE_INSTALL_LIBEXECDIR}/scan2lod)
