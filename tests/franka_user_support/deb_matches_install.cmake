# cmake -DBUILD=<CSP build dir> -DPREFIX=<what cmake --install wrote> -DOUT=<dir> -P deb_matches_install.cmake
# The Debian packages (CPack) install together the same files as `cmake --install`, and each says
# plainly what it is beside Franka's own libfranka package (docs/franka_api.md, "Debian packages"):
#   csp         no file on libfranka's paths (usr/include/franka, usr/include/research_interface,
#               usr/lib/cmake/Franka, usr/lib/libfranka.so*) and no Conflicts: installs beside it;
#   csp-franka  every file on those paths but no libfranka.so, Conflicts: libfranka, no Provides,
#               Depends: csp of the same version.
# Then dpkg itself unpacks them beside a stand-in libfranka package (below).
cmake_minimum_required(VERSION 3.25)   # IN_LIST
file(REMOVE_RECURSE ${OUT})
execute_process(COMMAND cpack -G DEB --config ${BUILD}/CPackConfig.cmake -B ${OUT} RESULT_VARIABLE result
                OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "cpack failed:\n${out}${err}")
endif()
file(GLOB debs ${OUT}/*.deb)

# The control field `field` of `deb` ("" when it has none).
function(control_field deb field out)
  execute_process(COMMAND dpkg-deb -f ${deb} ${field} OUTPUT_VARIABLE value RESULT_VARIABLE result
                  OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "dpkg-deb -f ${deb} ${field} failed")
  endif()
  set(${out} "${value}" PARENT_SCOPE)
endfunction()

set(libfranka_paths "^(include/franka/|include/research_interface/|lib/cmake/Franka/|lib/libfranka\\.so)")
set(packaged "")
set(names "")
foreach(deb IN LISTS debs)
  control_field(${deb} Package name)
  control_field(${deb} Version version)
  list(APPEND names ${name})
  execute_process(COMMAND dpkg-deb -x ${deb} ${OUT}/${name} RESULT_VARIABLE result)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "dpkg-deb -x ${deb} failed")
  endif()
  file(GLOB_RECURSE files RELATIVE ${OUT}/${name}/usr ${OUT}/${name}/usr/*)
  list(APPEND packaged ${files})
  set(on_libfranka_paths ${files})
  list(FILTER on_libfranka_paths INCLUDE REGEX "${libfranka_paths}")
  set(elsewhere ${files})
  list(FILTER elsewhere EXCLUDE REGEX "${libfranka_paths}")
  control_field(${deb} Conflicts conflicts)
  control_field(${deb} Provides provides)
  control_field(${deb} Replaces replaces)
  control_field(${deb} Depends depends)
  if(name STREQUAL "csp")
    if(on_libfranka_paths OR conflicts OR provides OR replaces)
      message(FATAL_ERROR "csp must install beside libfranka: files on its paths [${on_libfranka_paths}], "
                          "Conflicts [${conflicts}], Provides [${provides}], Replaces [${replaces}]")
    endif()
    if(NOT elsewhere MATCHES "(^|;)bin/csp(;|$)" OR NOT elsewhere MATCHES "share/csp/configs/scenarios/libfranka_panda.yaml")
      message(FATAL_ERROR "csp lacks the csp command or the scenarios: ${elsewhere}")
    endif()
  elseif(name STREQUAL "csp-franka")
    list(FILTER elsewhere EXCLUDE REGEX "^lib/libcsp_franka\\.so")
    if(elsewhere)
      message(FATAL_ERROR "csp-franka holds more than libfranka's API: ${elsewhere}")
    endif()
    foreach(expected include/franka/robot.h include/research_interface/robot/service_types.h
                     lib/cmake/Franka/FrankaConfig.cmake)
      if(NOT expected IN_LIST on_libfranka_paths)
        message(FATAL_ERROR "csp-franka lacks ${expected}")
      endif()
    endforeach()
    if(on_libfranka_paths MATCHES "lib/libfranka\\.so")
      message(FATAL_ERROR "csp-franka must not install libfranka.so (it is not libfranka's binary)")
    endif()
    if(NOT conflicts STREQUAL "libfranka" OR provides OR replaces)
      message(FATAL_ERROR "csp-franka: expected Conflicts: libfranka and no Provides or Replaces, got "
                          "Conflicts [${conflicts}], Provides [${provides}], Replaces [${replaces}]")
    endif()
    if(NOT depends MATCHES "(^|, )csp \\(= ${version}\\)(,|$)")
      message(FATAL_ERROR "csp-franka must depend on csp (= ${version}): Depends [${depends}]")
    endif()
  else()
    message(FATAL_ERROR "unexpected package ${name} (${deb})")
  endif()
endforeach()
list(SORT names)
if(NOT names STREQUAL "csp;csp-franka")
  message(FATAL_ERROR "expected the packages csp and csp-franka, got [${names}]")
endif()

# Together they install what `cmake --install` does, each file once.
file(GLOB_RECURSE installed RELATIVE ${PREFIX} ${PREFIX}/*)
list(SORT packaged)
list(SORT installed)
if(NOT packaged STREQUAL installed)
  set(only_package ${packaged})
  list(REMOVE_ITEM only_package ${installed})
  set(only_install ${installed})
  list(REMOVE_ITEM only_install ${packaged})
  message(FATAL_ERROR "the packages and the install differ\nonly in the packages: ${only_package}\n"
                      "only installed: ${only_install}\n(or a file is in both packages)")
endif()
list(LENGTH packaged files)
message(STATUS "csp and csp-franka: the same ${files} files as cmake --install")

# What dpkg does with them beside libfranka: a stand-in package named libfranka with files on its
# paths, unpacked into a dpkg database of its own (--root; --unpack runs no maintainer script).
# csp unpacks beside it; csp-franka is refused for its Conflicts; alone, csp and csp-franka unpack.
set(standin ${OUT}/libfranka_standin)
foreach(file usr/include/franka/robot.h usr/include/research_interface/robot/rbk_types.h
             usr/lib/cmake/Franka/FrankaConfig.cmake usr/lib/libfranka.so.0.15.0)
  file(WRITE ${standin}/${file} "libfranka's\n")
endforeach()
file(WRITE ${standin}/DEBIAN/control "Package: libfranka\nVersion: 0.15.0-1\nArchitecture: all\n"
     "Maintainer: CSP tests <csp@localhost>\nDescription: a stand-in with libfranka's file paths\n")
execute_process(COMMAND dpkg-deb --root-owner-group -b ${standin} ${OUT}/libfranka_standin.deb
                RESULT_VARIABLE result OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "dpkg-deb -b of the libfranka stand-in failed: ${err}")
endif()
# unpack(<root> <deb> <out var>): dpkg's exit code, then what it printed.
function(unpack root deb out)
  file(MAKE_DIRECTORY ${root}/var/lib/dpkg/info ${root}/var/lib/dpkg/updates)
  file(TOUCH ${root}/var/lib/dpkg/status)
  execute_process(COMMAND dpkg --root=${root} --force-not-root --log=/dev/null --unpack ${deb}
                  RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE error)
  set(${out} "${result}\n${output}${error}" PARENT_SCOPE)
endfunction()
file(GLOB csp_deb ${OUT}/csp_*.deb)
file(GLOB csp_franka_deb ${OUT}/csp-franka_*.deb)
unpack(${OUT}/beside ${OUT}/libfranka_standin.deb output)
unpack(${OUT}/beside ${csp_deb} output)
if(NOT output MATCHES "^0\n")
  message(FATAL_ERROR "csp does not unpack beside libfranka:\n${output}")
endif()
unpack(${OUT}/beside ${csp_franka_deb} output)
if(output MATCHES "^0\n" OR NOT output MATCHES "csp-franka conflicts with libfranka")
  message(FATAL_ERROR "csp-franka beside libfranka: expected dpkg to refuse it for its Conflicts:\n${output}")
endif()
unpack(${OUT}/alone ${csp_deb} output)
unpack(${OUT}/alone ${csp_franka_deb} output)
if(NOT output MATCHES "^0\n" OR NOT EXISTS ${OUT}/alone/usr/lib/cmake/Franka/FrankaConfig.cmake)
  message(FATAL_ERROR "csp-franka does not unpack after csp:\n${output}")
endif()
message(STATUS "dpkg: csp unpacks beside libfranka, csp-franka is refused there for its Conflicts")
