# Each public franka header compiles on its own (it includes what it uses) as C++${STANDARD} with
# -Wall -Wextra -Wpedantic -Werror, and franka::Robot / franka::Model are only pointers (their
# layout cannot depend on -march or Eigen's alignment; checked with and without -march=native).
# franka/active_control*.h need C++17 (std::optional in libfranka's signatures): under C++14 they
# must stop with their own #error message.
# cmake -DCXX=<compiler> -DSTANDARD=14|17|20 -DINCLUDE_DIR=<rt/franka/include> -DWORK_DIR=<dir> -P franka_headers.cmake
file(GLOB_RECURSE headers RELATIVE ${INCLUDE_DIR} ${INCLUDE_DIR}/*.h ${INCLUDE_DIR}/*.hpp)
file(MAKE_DIRECTORY ${WORK_DIR})
set(failures "")
foreach(header ${headers})
  string(MAKE_C_IDENTIFIER ${header} name)
  set(source ${WORK_DIR}/${name}_cxx${STANDARD}.cpp)
  set(text "#include <${header}>\n")
  if(header STREQUAL "franka/robot.h" OR header STREQUAL "franka/model.h")
    string(APPEND text "#include <memory>\n"
      "static_assert(sizeof(franka::Robot) == sizeof(void*) + sizeof(std::shared_ptr<int>), \"Robot: vptr + Impl\");\n")
  endif()
  if(header STREQUAL "franka/model.h")
    string(APPEND text "static_assert(sizeof(franka::Model) == sizeof(void*), \"Model: Impl only\");\n")
  endif()
  file(WRITE ${source} "${text}")
  set(flag_sets "-O0")
  if(header STREQUAL "franka/robot.h" OR header STREQUAL "franka/model.h")
    list(APPEND flag_sets "-march=native")
  endif()
  foreach(flags ${flag_sets})
    execute_process(COMMAND ${CXX} -std=c++${STANDARD} -fsyntax-only -Wall -Wextra -Wpedantic -Werror ${flags}
                            -I${INCLUDE_DIR} ${source}
                    RESULT_VARIABLE result ERROR_VARIABLE errors OUTPUT_QUIET)
    if(header MATCHES "^franka/active_" AND STANDARD EQUAL 14)
      if(result EQUAL 0 OR NOT errors MATCHES "needs C\\+\\+17")
        string(APPEND failures "${header} (C++14): expected its #error naming C++17, got:\n${errors}\n")
      endif()
    elseif(NOT result EQUAL 0)
      string(APPEND failures "${header} (C++${STANDARD} ${flags}):\n${errors}\n")
    endif()
  endforeach()
endforeach()
list(LENGTH headers count)
if(failures)
  message(FATAL_ERROR "franka headers that do not compile on their own:\n${failures}")
endif()
message(STATUS "${count} franka headers compile on their own as C++${STANDARD}")
