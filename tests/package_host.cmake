file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "install failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SRC}/examples/host -B ${WORK}/host -G Ninja
                        -DCMAKE_PREFIX_PATH=${WORK}/prefix RESULT_VARIABLE rc OUTPUT_VARIABLE o ERROR_VARIABLE e)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configure against the installed package failed:\n${o}\n${e}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK}/host RESULT_VARIABLE rc OUTPUT_VARIABLE o ERROR_VARIABLE e)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "host build failed:\n${o}\n${e}")
endif()
# The host's own device, command buffers and fence ring: 60 frames, 3 in flight, validation on (exit 3 on any
# message), the composed last frame checked against renderFrame.
execute_process(COMMAND ${WORK}/host/visbuf_host --frames 60 --in-flight 3 --validation
                RESULT_VARIABLE rc OUTPUT_VARIABLE o ERROR_VARIABLE e)
if(NOT rc EQUAL 0 OR NOT o MATCHES "60 frames recorded with 3 in flight" OR NOT o MATCHES "objects drawn")
  message(FATAL_ERROR "host run failed (${rc}):\n${o}\n${e}")
endif()
message(STATUS "${o}")

# The same host through pkg-config (no CMake on the host's side): visbuf.pc names the include folder, the
# static libraries and their dependencies' .pc files.
find_program(PKG_CONFIG pkg-config REQUIRED)
find_program(CXX_COMPILER NAMES c++ g++ REQUIRED)
set(ENV{PKG_CONFIG_PATH} ${WORK}/prefix/lib/pkgconfig)
execute_process(COMMAND ${PKG_CONFIG} --cflags --libs visbuf RESULT_VARIABLE rc OUTPUT_VARIABLE flags ERROR_VARIABLE e
                OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "pkg-config --cflags --libs visbuf failed:\n${e}")
endif()
separate_arguments(flags UNIX_COMMAND "${flags}")
execute_process(COMMAND ${CXX_COMPILER} ${SRC}/examples/host/main.cpp -o ${WORK}/visbuf_host_pc ${flags}
                RESULT_VARIABLE rc OUTPUT_VARIABLE o ERROR_VARIABLE e)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "host build through pkg-config failed (flags: ${flags}):\n${o}\n${e}")
endif()
execute_process(COMMAND ${WORK}/visbuf_host_pc RESULT_VARIABLE rc OUTPUT_VARIABLE o ERROR_VARIABLE e)
if(NOT rc EQUAL 0 OR NOT o MATCHES "objects drawn")
  message(FATAL_ERROR "pkg-config host run failed (${rc}):\n${o}\n${e}")
endif()
message(STATUS "pkg-config build: ${o}")
