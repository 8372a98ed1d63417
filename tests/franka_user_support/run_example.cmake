# cmake -DPROGRAM=<path> "-DARGS=<a b>" -DINPUT=<text for stdin> -DEXPECT=<ok | libfranka error name>
#       -P run_example.cmake
# Runs one of the user project's programs as its user would (robot hostname first) and checks its
# outcome: `ok` = it ends normally (exit code 0); an error name = it fails as on the real robot,
# with a non-zero exit code and libfranka's error name in what it prints.
get_filename_component(name ${PROGRAM} NAME)
separate_arguments(arguments UNIX_COMMAND "${ARGS}")
set(input_file ${CMAKE_CURRENT_BINARY_DIR}/${name}.stdin)
file(WRITE ${input_file} "${INPUT}")
execute_process(COMMAND ${PROGRAM} ${arguments} INPUT_FILE ${input_file} RESULT_VARIABLE result
                OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 300)
message("${out}${err}")
if(EXPECT STREQUAL "ok")
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "${name} ${ARGS}: expected a normal end, got exit status '${result}'")
  endif()
else()
  if(result EQUAL 0)
    message(FATAL_ERROR "${name} ${ARGS}: expected it to fail with ${EXPECT}, it ended normally")
  endif()
  string(FIND "${out}${err}" "${EXPECT}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${name} ${ARGS}: expected ${EXPECT} in its output")
  endif()
endif()
