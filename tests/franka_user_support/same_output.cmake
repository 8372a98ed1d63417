# cmake -DFIRST=<program> -DSECOND=<program> -P same_output.cmake
# Both programs print the same (here: the franka types' sizes and alignments under two sets of
# compiler flags).
execute_process(COMMAND ${FIRST} OUTPUT_VARIABLE first RESULT_VARIABLE r1)
execute_process(COMMAND ${SECOND} OUTPUT_VARIABLE second RESULT_VARIABLE r2)
if(NOT r1 EQUAL 0 OR NOT r2 EQUAL 0)
  message(FATAL_ERROR "a probe failed: ${FIRST} -> ${r1}, ${SECOND} -> ${r2}")
endif()
if(NOT first STREQUAL second)
  message(FATAL_ERROR "the layouts differ:\n${FIRST}:\n${first}\n${SECOND}:\n${second}")
endif()
message(STATUS "same layout:\n${first}")
