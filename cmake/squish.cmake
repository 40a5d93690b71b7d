# libsquish (Debian libsquish-dev) as the imported target visbuf_squish. Included by the top CMakeLists and by
# the installed visbufConfig.cmake, so a host linking visbuf::engine links the same library.
if(NOT TARGET visbuf_squish)
  find_path(SQUISH_INCLUDE_DIR squish.h REQUIRED)
  find_library(SQUISH_LIBRARY squish REQUIRED)
  add_library(visbuf_squish UNKNOWN IMPORTED)
  set_target_properties(visbuf_squish PROPERTIES IMPORTED_LOCATION "${SQUISH_LIBRARY}"
                                                 INTERFACE_INCLUDE_DIRECTORIES "${SQUISH_INCLUDE_DIR}")
endif()
