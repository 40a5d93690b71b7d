# `visbuf stress --reduced` end to end (the CI-sized stress suite): every bound holds, validation clean,
# both outputs written.
execute_process(COMMAND ${VISBUF} stress --reduced --validation --device cpu --assets ${ASSETS} -o ${OUT}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "visbuf stress --reduced failed (exit ${rc})")
endif()
foreach(f stress.json stress.md)
  if(NOT EXISTS ${OUT}/${f})
    message(FATAL_ERROR "missing ${OUT}/${f}")
  endif()
endforeach()
file(READ ${OUT}/stress.json json)
string(JSON pass GET "${json}" pass)
string(JSON cases LENGTH "${json}" cases)
if(NOT pass OR cases LESS 6)
  message(FATAL_ERROR "stress.json: pass=${pass}, ${cases} cases")
endif()
