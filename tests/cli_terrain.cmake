# `visbuf render --scene terrain`: a small heightfield on the default device with validation on. The default camera
# is low and grazing, so the terrain fills most of the frame; LOD and culling stay close to the exact image
# (--reference-full); bad --terrain-size values and options that do not apply are refused with the option named.
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${VISBUF} render --scene terrain --terrain-size 129 --size 320x180 --validation
                        --reference-full -o ${OUT}/terrain.png --json ${OUT}/terrain.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "render --scene terrain failed (${rc}):\n${out}\n${err}")
endif()
file(READ ${OUT}/terrain.json json)
string(JSON covered GET "${json}" coveredPixels)
string(JSON drawn GET "${json}" trianglesDrawn)
string(JSON psnr GET "${json}" reference error psnr)
math(EXPR half "320 * 180 / 2")
if(covered LESS_EQUAL half)
  message(FATAL_ERROR "the terrain covers ${covered} pixels, not more than half the frame (${half}):\n${out}")
endif()
# 2 x 128^2 = 32768 triangles at full detail: some drawn, never more than that.
if(drawn LESS_EQUAL 0 OR drawn GREATER 32768)
  message(FATAL_ERROR "triangles drawn: ${drawn} (expected 1..32768):\n${out}")
endif()
if(psnr LESS 35)
  message(FATAL_ERROR "PSNR against the exact image ${psnr} dB < 35:\n${out}")
endif()
string(FIND "${out}" "terrain: 1 objects, 1 meshes" at)
if(at EQUAL -1)
  message(FATAL_ERROR "the scene line does not name the terrain as one object:\n${out}")
endif()

# Refusals: a clear message naming the problem, exit code non-zero, before any rendering.
foreach(case "--scene;terrain;--terrain-size;1" "--scene;terrain;--terrain-size;8194"
             "--scene;city;--terrain-size;65" "--scene;terrain;--terrain-size;65;--objects;4")
  execute_process(COMMAND ${VISBUF} render ${case} --size 16x16 RESULT_VARIABLE rcb OUTPUT_VARIABLE outb
                  ERROR_VARIABLE errb)
  if(rcb EQUAL 0 OR NOT errb MATCHES "terrain-size|objects")
    message(FATAL_ERROR "render ${case} should fail naming the option, got ${rcb}: ${outb}${errb}")
  endif()
endforeach()
message(STATUS "render --scene terrain: ok\n${out}")
