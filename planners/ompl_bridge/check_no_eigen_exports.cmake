# cmake -DPROGRAM=<a program or library linking csp_ompl_bridge> -P check_no_eigen_exports.cmake
# None of its Eigen symbols may be dynamic: libompl.so would bind to them instead of its own
# (CMakeLists.txt, eigen_local.map; ompl/ompl#601).
execute_process(COMMAND nm -D --defined-only -C ${PROGRAM} OUTPUT_VARIABLE symbols RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "nm failed on ${PROGRAM}")
endif()
string(REGEX MATCHALL "[^\n]*Eigen::[^\n]*" exported "${symbols}")
list(LENGTH exported count)
if(count GREATER 0)
  list(GET exported 0 first)
  message(FATAL_ERROR "${PROGRAM} exports ${count} Eigen symbols, e.g. ${first}")
endif()
message(STATUS "${PROGRAM}: no Eigen symbol exported")
