# Run after `lcm-gen --python` (bridge/CMakeLists.txt): LCM 1.3.1's lcm-gen (Debian 12) decodes a boolean
# array as `map(bool, ...)`, in Python 3 a one-shot iterator that encode() cannot write back; LCM 1.5.0
# emits a list instead (lcm-proj/lcm commit 91ce7a2). This writes the generated lines in 1.5.0's form.
# Usage: cmake -DDIR=<the generated package's folder> -P lcm_gen_bool_arrays.cmake
file(GLOB sources ${DIR}/*.py)
foreach(source ${sources})
  file(READ ${source} text)
  string(REGEX REPLACE "= map\\(bool, (struct\\.unpack\\([^\n]*\\))\\)\n" "= [bool(x) for x in \\1]\n" fixed "${text}")
  if(NOT fixed STREQUAL text)
    file(WRITE ${source} "${fixed}")
  endif()
endforeach()
