# cmake -DSOURCE=<CSP source dir> -DOUT=<scratch dir> -P native_opt_in.cmake
# CSP builds portable unless asked: configured with no options, no compile command carries
# -march=native; configured with -DCSP_NATIVE=ON, `cmake --install` and `cpack` refuse before copying
# anything.
file(REMOVE_RECURSE ${OUT})
foreach(variant default native)
  set(args -S ${SOURCE} -B ${OUT}/${variant} -G Ninja -DCSP_BUILD_TESTS=OFF -DCSP_BUILD_BENCHMARKS=OFF
           -DCMAKE_EXPORT_COMPILE_COMMANDS=ON)
  if(variant STREQUAL "native")
    list(APPEND args -DCSP_NATIVE=ON)
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} ${args} RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "configuring CSP (${variant}) failed:\n${out}${err}")
  endif()
  file(READ ${OUT}/${variant}/compile_commands.json commands)
  string(FIND "${commands}" "-march=native" at)
  if(variant STREQUAL "default" AND NOT at EQUAL -1)
    message(FATAL_ERROR "the default build compiles with -march=native")
  endif()
  if(variant STREQUAL "native" AND at EQUAL -1)
    message(FATAL_ERROR "-DCSP_NATIVE=ON does not compile with -march=native")
  endif()
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} --install ${OUT}/native --prefix ${OUT}/native_install
                RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(result EQUAL 0)
  message(FATAL_ERROR "cmake --install of a CSP_NATIVE=ON build succeeded:\n${out}")
endif()
if(NOT err MATCHES "built with CSP_NATIVE=ON")
  message(FATAL_ERROR "cmake --install of a CSP_NATIVE=ON build failed without naming why:\n${err}")
endif()
if(EXISTS ${OUT}/native_install)
  message(FATAL_ERROR "the refused install still wrote ${OUT}/native_install")
endif()
# cpack installs each package's component on its own: every one must refuse.
execute_process(COMMAND cpack -G DEB --config ${OUT}/native/CPackConfig.cmake -B ${OUT}/native_packages
                RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
file(GLOB debs ${OUT}/native_packages/*.deb)
if(result EQUAL 0 OR debs OR NOT "${out}${err}" MATCHES "built with CSP_NATIVE=ON")
  message(FATAL_ERROR "cpack of a CSP_NATIVE=ON build did not refuse by name (exit ${result}, packages [${debs}]):\n${out}${err}")
endif()
message(STATUS "default build portable; a -march=native build refuses to install and to package")
