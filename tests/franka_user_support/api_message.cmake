# cmake -DPREFIX=<installed CSP> -DOUT=<dir> -P api_message.cmake
# A project against the installed package is told in one line which libfranka API it got and how
# to choose the other, and gets that API: asking nothing (0.15), find_package(Franka 0.9) (0.9),
# -DCSP_FRANKA_API_VERSION=900 (0.9); find_package(Franka 0.9 QUIET) prints nothing; a bad
# CSP_FRANKA_API_VERSION is refused by name.
file(REMOVE_RECURSE ${OUT})
# configure(<name> <out var> [cmake arguments...]): the exit code, then what cmake printed
function(configure name out)
  execute_process(COMMAND ${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR}/api_message -B ${OUT}/${name}
                          -DCMAKE_PREFIX_PATH=${PREFIX} ${ARGN}
                  RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE error)
  set(${out} "${result}\n${output}${error}" PARENT_SCOPE)
endfunction()
# expect(<name> <output> <the API line's version> <definition>)
function(expect name output version definition)
  string(REGEX MATCHALL "-- Franka: [^\n]*" lines "${output}")
  list(LENGTH lines count)
  if(NOT count EQUAL 1 OR NOT lines MATCHES "^-- Franka: CSP with libfranka's ${version} API \\(the [0-9.]+ API: .+\\)$")
    message(FATAL_ERROR "${name}: expected one line naming the ${version} API and how to choose the other:\n${output}")
  endif()
  if(NOT output MATCHES "definitions: CSP_FRANKA_API_VERSION=${definition}\n")
    message(FATAL_ERROR "${name}: expected CSP_FRANKA_API_VERSION=${definition}:\n${output}")
  endif()
endfunction()

configure(nothing output)
expect(nothing "${output}" 0.15 1500)
configure(asks_0_9 output -DASK=0.9)
expect(asks_0_9 "${output}" 0.9 900)
configure(sets_900 output -DCSP_FRANKA_API_VERSION=900)
expect(sets_900 "${output}" 0.9 900)
configure(asks_0_15 output -DASK=0.15)
expect(asks_0_15 "${output}" 0.15 1500)
configure(quiet output -DASK=0.9 -DQUIET=ON)
if(output MATCHES "-- Franka:" OR NOT output MATCHES "definitions: CSP_FRANKA_API_VERSION=900")
  message(FATAL_ERROR "quiet: expected no API line and the 0.9 API:\n${output}")
endif()
configure(bad output -DCSP_FRANKA_API_VERSION=1300)
if(output MATCHES "^0\n" OR NOT output MATCHES "CSP_FRANKA_API_VERSION is 1300: it must be 1500")
  message(FATAL_ERROR "bad: expected CSP_FRANKA_API_VERSION=1300 refused by name:\n${output}")
endif()
message(STATUS "the API line and the API chosen agree in all 6 configurations")
