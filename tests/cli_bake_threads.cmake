# `visbuf bake --threads N`: the mesh builds run in parallel, yet the pack is the same byte for byte whatever the
# thread count (results stored by mesh index, codecs pinned). Each asset is baked with 1 and with 4 threads and
# the two packs compared; the mesh progress lines of the parallel bake count 1..N once each.
file(MAKE_DIRECTORY ${OUT})
foreach(asset Fox/glTF/Fox.gltf CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb
              BoxTexturedNonPowerOfTwo/glTF/BoxTexturedNonPowerOfTwo.gltf SimpleMeshes/glTF/SimpleMeshes.gltf)
  get_filename_component(name ${asset} NAME_WE)
  foreach(threads 1 4)
    file(REMOVE ${OUT}/${name}_${threads}.vbp)
    execute_process(COMMAND ${VISBUF} bake ${ASSETS}/${asset} -o ${OUT}/${name}_${threads}.vbp --threads ${threads}
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/${name}_${threads}.vbp)
      message(FATAL_ERROR "bake ${asset} --threads ${threads} failed (${rc}):\n${out}\n${err}")
    endif()
  endforeach()
  execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUT}/${name}_1.vbp ${OUT}/${name}_4.vbp RESULT_VARIABLE same)
  if(NOT same EQUAL 0)
    message(FATAL_ERROR "${asset}: the packs baked with 1 and 4 threads differ")
  endif()
  # stderr is not a terminal here: the last progress line of the mesh stage reports every mesh done.
  string(REGEX MATCHALL "built mesh [0-9]+/[0-9]+" lines "${err}")
  list(GET lines -1 last)
  if(NOT last MATCHES "built mesh ([0-9]+)/([0-9]+)" OR NOT CMAKE_MATCH_1 EQUAL CMAKE_MATCH_2)
    message(FATAL_ERROR "${asset}: the mesh progress did not end at done = total:\n${err}")
  endif()
  message(STATUS "${asset}: identical packs with 1 and 4 threads (${last})")
endforeach()
# --threads takes 0 (all cores) and refuses a non-number naming the option (exit 1, as the other option checks).
execute_process(COMMAND ${VISBUF} bake ${ASSETS}/Fox/glTF/Fox.gltf -o ${OUT}/Fox_0.vbp --threads 0 --no-textures
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "bake --threads 0 failed (${rc}):\n${err}")
endif()
execute_process(COMMAND ${VISBUF} bake ${ASSETS}/Fox/glTF/Fox.gltf -o ${OUT}/Fox_x.vbp --threads many
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "--threads" OR EXISTS ${OUT}/Fox_x.vbp)
  message(FATAL_ERROR "bake --threads many: expected exit 1 naming --threads, got ${rc}:\n${err}")
endif()
