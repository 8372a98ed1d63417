# The reference-reader test: a short emulated session exported by `csp log export --format mcap`
# (from its LCM log, with the scene of its scenario; and from its CSV joint log) and read with npm's
# @mcap/core (read_with_mcap_core.mjs); and the other way: the file written again by @mcap/core's
# writer (chunked, and without chunks; rewrite_with_mcap_core.mjs) is read by CSP, whose export of
# it is the first file byte for byte. Fails, never skips, when node or the module is missing.
#   cmake -DCSP=csp -DNODE=node -DSOURCE=<source dir> -DOUT=<directory> -P export_and_read.cmake
if(NOT NODE OR NOT EXISTS "${NODE}")
  message(FATAL_ERROR "node is missing (${NODE}): install Node.js and run `npm ci --prefix view/web`")
endif()
if(NOT EXISTS "${SOURCE}/view/web/node_modules/@mcap/core")
  message(FATAL_ERROR "@mcap/core is missing: run `npm ci --prefix view/web`")
endif()
file(MAKE_DIRECTORY "${OUT}")

function(run_checked)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}${err}")
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "failed (${result}): ${ARGN}")
  endif()
endfunction()

run_checked("${CSP}" emulate "${SOURCE}/configs/scenarios/medical/ultrasound_abdomen_scan.yaml" --duration 0.3
            --log "${OUT}/session.csv" --lcm-log "${OUT}/session.lcmlog")
file(STRINGS "${OUT}/session.csv" lines)
list(LENGTH lines line_count)
math(EXPR rows "${line_count} - 1")   # the header

run_checked("${CSP}" log export "${OUT}/session.lcmlog" --format mcap --out "${OUT}/from_lcm.mcap")
run_checked("${NODE}" "${SOURCE}/tests/mcap/read_with_mcap_core.mjs" "${OUT}/from_lcm.mcap" ${rows} 1)
run_checked("${CSP}" log export "${OUT}/session.csv" --format mcap --out "${OUT}/from_csv.mcap")
run_checked("${NODE}" "${SOURCE}/tests/mcap/read_with_mcap_core.mjs" "${OUT}/from_csv.mcap" ${rows} 0)

foreach(chunked 1 0)
  set(rewritten "${OUT}/rewritten_${chunked}.mcap")
  run_checked("${NODE}" "${SOURCE}/tests/mcap/rewrite_with_mcap_core.mjs" "${OUT}/from_lcm.mcap" "${rewritten}" ${chunked})
  run_checked("${CSP}" log export "${rewritten}" --format mcap --out "${OUT}/again_${chunked}.mcap")
  run_checked("${CMAKE_COMMAND}" -E compare_files "${OUT}/from_lcm.mcap" "${OUT}/again_${chunked}.mcap")
endforeach()
