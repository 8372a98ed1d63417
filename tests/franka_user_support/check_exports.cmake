# cmake -DLIBRARY=<libcsp_franka.so> -P check_exports.cmake
# Every dynamic symbol the library defines belongs to libfranka's API (namespace franka), so a
# program linking it sees libfranka's interface and nothing of CSP, Eigen or yaml-cpp.
execute_process(COMMAND nm -D --defined-only -C ${LIBRARY} OUTPUT_VARIABLE symbols RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "nm failed on ${LIBRARY}")
endif()
string(REPLACE "\n" ";" lines "${symbols}")
set(count 0)
foreach(line IN LISTS lines)
  if(line STREQUAL "")
    continue()
  endif()
  # "<address> <type> <name>"
  string(REGEX REPLACE "^[0-9a-f]+ [A-Za-z] " "" name "${line}")
  if(name MATCHES "^(franka::|typeinfo for franka::|typeinfo name for franka::|vtable for franka::|VTT for franka::)")
    math(EXPR count "${count} + 1")
  elseif(name MATCHES "^(CSP_FRANKA_|_init$|_fini$)")
    # the version node and the ELF init/fini entry points
  else()
    message(FATAL_ERROR "libcsp_franka exports a symbol outside libfranka's API: ${name}")
  endif()
endforeach()
if(count LESS 50)
  message(FATAL_ERROR "libcsp_franka exports only ${count} franka:: symbols")
endif()
message(STATUS "${count} symbols, all in namespace franka")
