# `visbuf bake` on 40 copies of one triangle (tests/data/stacked_triangles.gltf): a repeat of an earlier triangle's
# corners (same winding) covers the same pixels at the same depth, so the mesh build keeps one: the pack holds one
# triangle and 3 vertices, the JSON summary says 40 in and 1 out, and there is no warning (nothing was left that a
# simplifier could not reduce). Before the copies were dropped this mesh stalled every simplifier.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${VISBUF} bake ${DATA}/stacked_triangles.gltf -o ${OUT}/stacked.vbp --json ${OUT}/stacked.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "bake failed (${rc}):\n${out}\n${err}")
endif()
if(err MATCHES "warning: ")
  message(FATAL_ERROR "a warning for a mesh that reduces to one triangle:\n${err}")
endif()
file(READ ${OUT}/stacked.json json)
string(JSON stalled GET "${json}" meshes 0 simplificationStalled)
string(JSON lods LENGTH "${json}" meshes 0 lods)
string(JSON trianglesIn GET "${json}" meshes 0 trianglesIn)
string(JSON trianglesOut GET "${json}" meshes 0 lods 0 triangles)
string(JSON vertices GET "${json}" meshes 0 vertices)
if(stalled OR NOT lods EQUAL 1 OR NOT trianglesIn EQUAL 40 OR NOT trianglesOut EQUAL 1 OR NOT vertices EQUAL 3)
  message(FATAL_ERROR "stacked.json: simplificationStalled '${stalled}', ${lods} LOD(s), ${trianglesIn} -> "
                      "${trianglesOut} triangles, ${vertices} vertices (expected false, 1, 40 -> 1, 3)")
endif()
