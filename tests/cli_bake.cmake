# visbuf bake as a user runs it: a real asset to a pack, the pack rendered; bad input exits 1, usage 2,
# and a failed bake leaves no file behind.
file(MAKE_DIRECTORY ${OUT})
file(REMOVE ${OUT}/truck.vbp)
execute_process(COMMAND ${VISBUF} bake ${ASSETS}/CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb -o ${OUT}/truck.vbp
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/truck.vbp)
  message(FATAL_ERROR "bake failed (${rc}):\n${out}\n${err}")
endif()
execute_process(COMMAND ${VISBUF} render --scene ${OUT}/truck.vbp --size 160x120 --validation -o ${OUT}/truck.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE out2 ERROR_VARIABLE err2)
if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/truck.png)
  message(FATAL_ERROR "render of the pack failed (${rc}):\n${out2}\n${err2}")
endif()
# zstd sections (the default) against the same scene stored raw (--compression-level 0): a smaller file whose
# texels and geometry load to the same bytes, so the rendered image is bit-identical.
file(REMOVE ${OUT}/truck_raw.vbp)
execute_process(COMMAND ${VISBUF} bake ${ASSETS}/CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb -o ${OUT}/truck_raw.vbp
                        --compression-level 0
                RESULT_VARIABLE rc OUTPUT_VARIABLE outr ERROR_VARIABLE errr)
execute_process(COMMAND ${VISBUF} render --scene ${OUT}/truck_raw.vbp --size 160x120 --validation
                        -o ${OUT}/truck_raw.png RESULT_VARIABLE rc2 OUTPUT_VARIABLE outr2 ERROR_VARIABLE errr2)
if(NOT rc EQUAL 0 OR NOT rc2 EQUAL 0)
  message(FATAL_ERROR "raw bake or render failed (${rc}, ${rc2}):\n${outr}\n${errr}\n${outr2}\n${errr2}")
endif()
file(SIZE ${OUT}/truck.vbp zbytes)
file(SIZE ${OUT}/truck_raw.vbp rawbytes)
file(SHA256 ${OUT}/truck.png zimage)
file(SHA256 ${OUT}/truck_raw.png rawimage)
if(NOT zbytes LESS rawbytes OR NOT zimage STREQUAL rawimage)
  message(FATAL_ERROR "zstd pack ${zbytes} bytes against ${rawbytes} raw; images ${zimage} / ${rawimage} must match")
endif()
# --quantize: the summary and the JSON carry the measured error, and the quantised pack renders.
file(REMOVE ${OUT}/truck_q.vbp ${OUT}/truck_q.json)
execute_process(COMMAND ${VISBUF} bake ${ASSETS}/CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb -o ${OUT}/truck_q.vbp
                        --quantize --no-textures --json ${OUT}/truck_q.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE outq ERROR_VARIABLE errq)
if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/truck_q.vbp OR NOT outq MATCHES "position error: max")
  message(FATAL_ERROR "quantised bake failed (${rc}):\n${outq}\n${errq}")
endif()
file(READ ${OUT}/truck_q.json jq)
string(JSON qmax GET "${jq}" quantization maxPositionError)
string(JSON qsaved GET "${jq}" quantization bytesSaved)
if(NOT qsaved GREATER 0)
  message(FATAL_ERROR "quantised bake JSON: bytesSaved ${qsaved}, maxPositionError ${qmax}")
endif()
execute_process(COMMAND ${VISBUF} render --scene ${OUT}/truck_q.vbp --size 160x120 --validation -o ${OUT}/truck_q.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE out3 ERROR_VARIABLE err3)
if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/truck_q.png)
  message(FATAL_ERROR "render of the quantised pack failed (${rc}):\n${out3}\n${err3}")
endif()
# Rigid node animation through the pack: CesiumMilkTruck's wheels (rotation clips on unskinned nodes) are rigid
# objects (no skinning) that the frame places by their clip, so the images at two times differ: seen from the side,
# the textured hubs turn by about 112 degrees between t = 0 and 0.4. (The colour PNG is compared: the ID TIFF
# carries a timestamp, so its bytes differ between any two runs.)
foreach(t 0 0.4)
  execute_process(COMMAND ${VISBUF} render --scene ${OUT}/truck.vbp --size 320x240 --validation --time ${t}
                          --camera-pos 6,1.2,0 --camera-target 0,1,0 --json ${OUT}/truck_${t}.json
                          -o ${OUT}/truck_${t}.png
                  RESULT_VARIABLE rc OUTPUT_VARIABLE outt ERROR_VARIABLE errt)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "render of the truck pack at t=${t} failed (${rc}):\n${outt}\n${errt}")
  endif()
endforeach()
file(SHA256 ${OUT}/truck_0.png image0)
file(SHA256 ${OUT}/truck_0.4.png image1)
if(image0 STREQUAL image1)
  message(FATAL_ERROR "CesiumMilkTruck: the same image at t=0 and t=0.4 (its wheels do not turn)")
endif()
# --instances N on a pack: N copies of its scene (5 objects each: 3 body materials, 2 wheels).
execute_process(COMMAND ${VISBUF} render --scene ${OUT}/truck.vbp --instances 3 --time 0.25 --size 160x120
                        --validation --json ${OUT}/truck_x3.json -o ${OUT}/truck_x3.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE outx ERROR_VARIABLE errx)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "render of 3 truck pack instances failed (${rc}):\n${outx}\n${errx}")
endif()
file(READ ${OUT}/truck_x3.json jx)
string(JSON xobjects GET "${jx}" objects)
if(NOT xobjects EQUAL 15)
  message(FATAL_ERROR "--instances 3 on the truck pack: ${xobjects} objects, expected 15")
endif()
# Animated morph targets through a pack (version 4 morph sections): --skin-check reads the morphed instance back
# against the CPU's double-precision morph + skinning; at t = 1 s AnimatedMorphCube's weights are non-zero.
file(REMOVE ${OUT}/morph.vbp ${OUT}/morph.json)
execute_process(COMMAND ${VISBUF} bake ${ASSETS}/AnimatedMorphCube/glTF/AnimatedMorphCube.gltf -o ${OUT}/morph.vbp
                RESULT_VARIABLE rc OUTPUT_VARIABLE outm ERROR_VARIABLE errm)
if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/morph.vbp)
  message(FATAL_ERROR "bake of AnimatedMorphCube failed (${rc}):\n${outm}\n${errm}")
endif()
execute_process(COMMAND ${VISBUF} render --scene ${OUT}/morph.vbp --size 160x120 --validation --time 1
                        --skin-check 1 --json ${OUT}/morph.json -o ${OUT}/morph.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE outm ERROR_VARIABLE errm)
if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/morph.json)
  message(FATAL_ERROR "render of the morph pack failed (${rc}):\n${outm}\n${errm}")
endif()
file(READ ${OUT}/morph.json jm)
string(JSON minstances GET "${jm}" skinCheck instances)
string(JSON moutside GET "${jm}" skinCheck outside)
string(JSON mpos GET "${jm}" skinCheck maxPositionError)
if(NOT minstances EQUAL 1 OR NOT moutside EQUAL 0 OR mpos GREATER 1e-4)
  message(FATAL_ERROR "morph skin check: ${minstances} instances, ${moutside} outside, position error ${mpos}")
endif()
execute_process(COMMAND ${VISBUF} bake ${OUT}/missing.glb -o ${OUT}/missing.vbp RESULT_VARIABLE rc ERROR_VARIABLE e OUTPUT_QUIET)
if(NOT rc EQUAL 1 OR EXISTS ${OUT}/missing.vbp)
  message(FATAL_ERROR "a missing input must exit 1 and write nothing (got ${rc}): ${e}")
endif()
execute_process(COMMAND ${VISBUF} bake --no-such-option RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(NOT rc EQUAL 2)
  message(FATAL_ERROR "a usage error must exit 2 (got ${rc})")
endif()
execute_process(COMMAND ${VISBUF} bake --lod-count abc RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(NOT rc EQUAL 1)
  message(FATAL_ERROR "an option value that is not a number is bad input, exit 1 (got ${rc})")
endif()
message(STATUS "${out}")
