# METIS (Debian libmetis-dev: graph partitioning of the cluster LOD build, engine/scene/cluster_lod_groups.cpp) as
# the imported target visbuf_metis. Debian ships no CMake config or pkg-config file for it, so the header and the
# library are found directly. Included by the top CMakeLists and by the installed visbufConfig.cmake.
if(NOT TARGET visbuf_metis)
  find_path(METIS_INCLUDE_DIR metis.h REQUIRED)
  find_library(METIS_LIBRARY metis REQUIRED)
  add_library(visbuf_metis UNKNOWN IMPORTED)
  set_target_properties(visbuf_metis PROPERTIES IMPORTED_LOCATION "${METIS_LIBRARY}"
                                                INTERFACE_INCLUDE_DIRECTORIES "${METIS_INCLUDE_DIR}")
endif()
