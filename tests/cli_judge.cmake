# `visbuf render --judge`: both paths judged against the exact colour, the heat map and the JSON summary written,
# textured pixels judged too, and the combinations it cannot judge refused with a message.
file(MAKE_DIRECTORY ${OUT})
file(REMOVE ${OUT}/heat.png ${OUT}/stats.json)
# The city with LOD on (the judge reads the LOD each object was drawn at) and validation on.
execute_process(COMMAND ${VISBUF} render --scene city --size 200x120 --validation -o ${OUT}/frame.png
                        --judge ${OUT}/heat.png --json ${OUT}/stats.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "visbuf render --judge failed (${rc}):\n${out}\n${err}")
endif()
if(NOT EXISTS ${OUT}/heat.png OR NOT out MATCHES "judge +visbuf +vs exact: max" OR NOT out MATCHES "forward closer at")
  message(FATAL_ERROR "--judge: no heat map or no summary:\n${out}")
endif()
file(READ ${OUT}/stats.json json)
string(JSON covered GET "${json}" judge covered)
string(JSON judged GET "${json}" judge judged)
string(JSON visbufMax GET "${json}" judge visbuf maxAbs)
string(JSON forwardMax GET "${json}" judge forward maxAbs)
if(covered LESS 1000 OR NOT judged EQUAL covered)
  message(FATAL_ERROR "--judge: the untextured city must be judged at every covered pixel (${judged} of ${covered})")
endif()
# The Shading tests' exact-colour bounds (tests/gpu/test_shading.cpp): rgba16f rounding plus float shading.
if(visbufMax GREATER 1e-3 OR forwardMax GREATER 2e-3)
  message(FATAL_ERROR "--judge: visbuf max ${visbufMax}, forward max ${forwardMax} against the exact colour")
endif()
# Textured materials: judged too (the shader's filtering with the exact uv derivatives).
execute_process(COMMAND ${VISBUF} render --scene city --materials 4 --size 160x90 -o ${OUT}/textured.png
                        --judge ${OUT}/heat_textured.png --json ${OUT}/textured.json
                RESULT_VARIABLE rct OUTPUT_VARIABLE outt ERROR_VARIABLE errt)
if(NOT rct EQUAL 0)
  message(FATAL_ERROR "visbuf render --materials 4 --judge failed (${rct}):\n${outt}\n${errt}")
endif()
file(READ ${OUT}/textured.json tjson)
string(JSON tcovered GET "${tjson}" judge covered)
string(JSON tjudged GET "${tjson}" judge judged)
string(JSON tvisbufMax GET "${tjson}" judge visbuf maxAbs)
# PixelJudge.JudgesTexturedMaterials's bound (tests/gpu/test_pixel_judge.cpp).
if(NOT tjudged EQUAL tcovered OR tvisbufMax GREATER 3e-3)
  message(FATAL_ERROR "--judge, textured: ${tjudged} of ${tcovered} judged, visbuf max ${tvisbufMax}:\n${outt}")
endif()
# MSAA: the resolves against the exact one (the mean over the sample locations), every covered pixel judged.
execute_process(COMMAND ${VISBUF} render --scene city --msaa 4 --size 160x90 -o ${OUT}/msaa.png
                        --judge ${OUT}/heat_msaa.png --json ${OUT}/msaa.json
                RESULT_VARIABLE rcm OUTPUT_VARIABLE outm ERROR_VARIABLE errm)
if(NOT rcm EQUAL 0)
  message(FATAL_ERROR "visbuf render --msaa 4 --judge failed (${rcm}):\n${outm}\n${errm}")
endif()
file(READ ${OUT}/msaa.json mjson)
string(JSON mcovered GET "${mjson}" judge covered)
string(JSON mjudged GET "${mjson}" judge judged)
string(JSON medges GET "${mjson}" judge coverageMismatch)
string(JSON mvisbufMean GET "${mjson}" judge visbuf meanAbs)
string(JSON mforwardMean GET "${mjson}" judge forward meanAbs)
if(NOT mjudged EQUAL mcovered OR medges LESS 1 OR NOT outm MATCHES "edge pixels" OR mvisbufMean GREATER mforwardMean)
  message(FATAL_ERROR "--msaa 4 --judge: ${mjudged} of ${mcovered} judged, ${medges} edges, visbuf mean "
                      "${mvisbufMean} against forward ${mforwardMean}:\n${outm}")
endif()
# Refused: usage errors (2) name --judge; a heat map that is not an image: bad input (1).
foreach(args "--path;gbuffer" "--moving;0.1")
  execute_process(COMMAND ${VISBUF} render --size 64x64 ${args} --judge ${OUT}/refused.png
                  RESULT_VARIABLE rcr ERROR_VARIABLE errr OUTPUT_QUIET)
  if(NOT rcr EQUAL 2 OR NOT errr MATCHES "--judge")
    message(FATAL_ERROR "--judge with ${args} should be refused (2) naming --judge, got ${rcr}: ${errr}")
  endif()
endforeach()
execute_process(COMMAND ${VISBUF} render --size 64x64 --judge ${OUT}/heat.jpg RESULT_VARIABLE rcj ERROR_VARIABLE errj
                OUTPUT_QUIET)
if(NOT rcj EQUAL 1 OR NOT errj MATCHES "heat map")
  message(FATAL_ERROR "--judge heat.jpg should be refused (1), got ${rcj}: ${errj}")
endif()
if(EXISTS ${OUT}/refused.png)
  message(FATAL_ERROR "a refused --judge wrote its heat map")
endif()
message(STATUS "visbuf render --judge: ok\n${out}")
