# visbuf render --moving / --churn: the scene changes every frame through the renderer's update API; the JSON
# reports each frame's changes, uploaded bytes (68 per changed object: its record and ID) and culling counters.
file(MAKE_DIRECTORY ${OUT})
file(REMOVE ${OUT}/moving.json)
execute_process(COMMAND ${VISBUF} render --objects 4000 --size 160x120 --frames 12 --moving 0.1 --churn 0.002
                        --validation -o ${OUT}/moving.png --json ${OUT}/moving.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "scene changes")
  message(FATAL_ERROR "render --moving failed (${rc}):\n${out}\n${err}")
endif()
file(READ ${OUT}/moving.json j)
string(JSON frames LENGTH "${j}" perFrame)
if(NOT frames EQUAL 12)
  message(FATAL_ERROR "perFrame has ${frames} entries, not 12:\n${j}")
endif()
math(EXPR last "${frames} - 1")
foreach(i RANGE ${last})
  string(JSON moved GET "${j}" perFrame ${i} moved)
  string(JSON added GET "${j}" perFrame ${i} added)
  string(JSON removed GET "${j}" perFrame ${i} removed)
  string(JSON updated GET "${j}" perFrame ${i} objectsUpdated)
  string(JSON bytes GET "${j}" perFrame ${i} uploadedBytes)
  string(JSON tested GET "${j}" perFrame ${i} objectsTested)
  math(EXPR expect "${updated} * 68")
  if(moved LESS 300 OR NOT added EQUAL 8 OR NOT removed EQUAL 8 OR updated LESS moved OR NOT bytes EQUAL expect
     OR tested LESS 3000)
    message(FATAL_ERROR "frame ${i}: moved ${moved}, added ${added}, removed ${removed}, ${updated} records, "
                        "${bytes} bytes, ${tested} tested")
  endif()
endforeach()
# Out of range: bad input (1); with a fixed-scene reference: usage (2).
execute_process(COMMAND ${VISBUF} render --objects 100 --moving 1.5 -o "" RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "moving")
  message(FATAL_ERROR "--moving 1.5: exit ${rc}, expected 1 naming the option:\n${err}")
endif()
execute_process(COMMAND ${VISBUF} render --objects 100 --moving 0.1 --reference -o "" RESULT_VARIABLE rc
                ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "reference")
  message(FATAL_ERROR "--moving with --reference: exit ${rc}, expected 2:\n${err}")
endif()
