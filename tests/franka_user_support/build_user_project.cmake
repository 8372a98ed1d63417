# cmake -DSOURCE=<tests/franka_user> -DBINARY=<dir> -DPREFIX=<installed CSP> [-DFLAGS=...] [-DAPI=900]
#       -P build_user_project.cmake
# Configures and builds the libfranka-style user project against an installed CSP, as its user
# would: find_package(Franka) through CMAKE_PREFIX_PATH, the user's own compiler flags.
set(args -S ${SOURCE} -B ${BINARY} -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${PREFIX}
         "-DCMAKE_CXX_FLAGS=${FLAGS}")
if(DEFINED API)
  list(APPEND args -DCSP_FRANKA_API_VERSION=${API})
endif()
execute_process(COMMAND ${CMAKE_COMMAND} ${args} RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "configuring the user project failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BINARY} RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "building the user project failed")
endif()
