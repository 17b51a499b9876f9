# `cmake --install` into a fresh prefix gives a kozu that works from anywhere: run from an unrelated folder, it
# reports its version, renders the built-in demo, and renders an installed showcase scene (which reads its mesh
# and texture files relative to itself). Arguments: KOZU_BINARY_DIR (the build), KOZU_WORK (a scratch folder).
file(REMOVE_RECURSE ${KOZU_WORK})
file(MAKE_DIRECTORY ${KOZU_WORK}/elsewhere)
execute_process(COMMAND ${CMAKE_COMMAND} --install ${KOZU_BINARY_DIR} --prefix ${KOZU_WORK}/prefix
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc})")
endif()
set(kozu ${KOZU_WORK}/prefix/bin/kozu)
foreach(f ${kozu} ${KOZU_WORK}/prefix/share/kozu/scenes/cornell.json ${KOZU_WORK}/prefix/share/doc/kozu/README.md)
  if(NOT EXISTS ${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()

function(run_kozu)
  execute_process(COMMAND ${kozu} ${ARGN} WORKING_DIRECTORY ${KOZU_WORK}/elsewhere RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "kozu ${ARGN}: exit ${rc}\n${out}${err}")
  endif()
endfunction()
run_kozu(--version)
run_kozu(render --demo --resolution 32x18 --spp 1 --quiet -o demo.png)
run_kozu(render ${KOZU_WORK}/prefix/share/kozu/scenes/stained_glass.json --resolution 32x32 --spp 1 --quiet
         -o glass.exr)
foreach(f demo.png glass.exr)
  if(NOT EXISTS ${KOZU_WORK}/elsewhere/${f})
    message(FATAL_ERROR "kozu wrote no ${f}")
  endif()
endforeach()
file(REMOVE_RECURSE ${KOZU_WORK})
