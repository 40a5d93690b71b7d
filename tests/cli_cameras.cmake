# `visbuf render --camera`: the list of a glTF file's cameras, rendering from one of them, and clear refusals of a
# camera the file does not have or an unknown value. The file (a square seen by a perspective camera with an aspect
# ratio and an orthographic one) is written here.
file(MAKE_DIRECTORY ${OUT})
file(WRITE ${OUT}/cameras.gltf "{\"asset\": {\"version\": \"2.0\"}, \"buffers\": [{\"byteLength\": 62, \"uri\": \"data:application/octet-stream;base64,AACAvwAAgL8AAAAAAACAPwAAgL8AAAAAAACAPwAAgD8AAAAAAACAvwAAgD8AAAAAAAABAAIAAAACAAMAAAA=\"}], \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 48}, {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 12}], \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\", \"min\": [-1, -1, 0], \"max\": [1, 1, 0]}, {\"bufferView\": 1, \"componentType\": 5123, \"count\": 6, \"type\": \"SCALAR\"}], \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1}]}], \"cameras\": [{\"name\": \"persp\", \"type\": \"perspective\", \"perspective\": {\"yfov\": 0.7, \"aspectRatio\": 1.5, \"znear\": 0.1, \"zfar\": 50}}, {\"type\": \"orthographic\", \"orthographic\": {\"xmag\": 1.5, \"ymag\": 1.0, \"znear\": 0, \"zfar\": 20}}], \"nodes\": [{\"mesh\": 0}, {\"camera\": 0, \"translation\": [0, 0, 4]}, {\"name\": \"top\", \"camera\": 1, \"translation\": [0, 0, 3]}], \"scenes\": [{\"nodes\": [0, 1, 2]}], \"scene\": 0}")
execute_process(COMMAND ${VISBUF} render --scene ${OUT}/cameras.gltf --camera list
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "0  'persp'  perspective yfov 40.11 deg aspect 1.5 znear 0.1 zfar 50"
   OR NOT out MATCHES "1  'top'  orthographic xmag 1.5 ymag 1 znear 0 zfar 20")
  message(FATAL_ERROR "--camera list (${rc}):\n${out}\n${err}")
endif()
execute_process(COMMAND ${VISBUF} render --scene ${OUT}/cameras.gltf --camera
                RESULT_VARIABLE rc OUTPUT_VARIABLE out2 ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out2 STREQUAL out)
  message(FATAL_ERROR "--camera alone should list the cameras (${rc}):\n${out2}\n${err}")
endif()
foreach(camera gltf gltf:1)
  execute_process(COMMAND ${VISBUF} render --scene ${OUT}/cameras.gltf --camera ${camera} --size 96x64 --validation
                          -o ${OUT}/frame.png RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/frame.png)
    message(FATAL_ERROR "--camera ${camera} failed (${rc}):\n${out}\n${err}")
  endif()
  file(REMOVE ${OUT}/frame.png)
endforeach()
execute_process(COMMAND ${VISBUF} render --scene ${OUT}/cameras.gltf --camera gltf:2 RESULT_VARIABLE rc
                ERROR_VARIABLE err OUTPUT_QUIET)
if(rc EQUAL 0 OR NOT err MATCHES "2 camera")
  message(FATAL_ERROR "--camera gltf:2 should be refused naming the 2 cameras (${rc}): ${err}")
endif()
execute_process(COMMAND ${VISBUF} render --scene ${OUT}/cameras.gltf --camera front RESULT_VARIABLE rc
                ERROR_VARIABLE err OUTPUT_QUIET)
if(rc EQUAL 0 OR NOT err MATCHES "expected gltf, gltf:N or list")
  message(FATAL_ERROR "--camera front should be refused (${rc}): ${err}")
endif()
