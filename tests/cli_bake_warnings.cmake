# `visbuf bake` on a mesh meshoptimizer cannot simplify (tests/data/stacked_triangles.gltf: 40 copies of one
# triangle; every simplification keeps all of them or none): the pack is written, with a warning that names the
# mesh and the triangle count the chain stopped at, and the JSON summary marks the mesh.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${VISBUF} bake ${DATA}/stacked_triangles.gltf -o ${OUT}/stacked.vbp --json ${OUT}/stacked.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "bake failed (${rc}):\n${out}\n${err}")
endif()
if(NOT err MATCHES "warning: mesh 0 '[^']*' cannot be simplified below 40 triangles")
  message(FATAL_ERROR "no warning for the mesh that cannot be simplified:\n${err}")
endif()
file(READ ${OUT}/stacked.json json)
string(JSON stalled GET "${json}" meshes 0 simplificationStalled)
string(JSON lods LENGTH "${json}" meshes 0 lods)
if(NOT stalled OR NOT lods EQUAL 1)
  message(FATAL_ERROR "stacked.json: simplificationStalled '${stalled}', ${lods} LOD(s) (expected true, 1)")
endif()
