# Part of `cmake --install`: writes the showcase files that are generated, not stored, into the installed scenes
# folder, so that every installed scene renders from any folder. Set before it runs (CMakeLists.txt): KOZU_EXE (the
# kozu just built), KOZU_SOURCE_DIR, KOZU_PYTHON (python3, empty when configure found none), KOZU_SCENES_DIR (the
# scenes folder relative to the prefix).
#  - scenes/volumes/bush.kvox (about 3 s): the voxelized bush, exactly as scripts/make-volumes.sh writes it into a
#    clone (the smoke, yarn and fabric scenes generate their voxels at load: "procedural");
#  - scenes/showcase.glb (0.6 MB, about 2 s): the glTF showcase, from scripts/make-showcase-gltf.py.
if(NOT IS_ABSOLUTE "${KOZU_SCENES_DIR}")
  set(scenes "$ENV{DESTDIR}${CMAKE_INSTALL_PREFIX}/${KOZU_SCENES_DIR}")
else()
  set(scenes "$ENV{DESTDIR}${KOZU_SCENES_DIR}")
endif()

function(kozu_generate what)
  message(STATUS "Generating: ${what}")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "generating ${what} failed (${rc}): ${ARGN}\n${out}")
  endif()
  set(CMAKE_INSTALL_MANIFEST_FILES ${CMAKE_INSTALL_MANIFEST_FILES} "${what}" PARENT_SCOPE)
endfunction()

file(MAKE_DIRECTORY "${scenes}/volumes")
kozu_generate("${scenes}/volumes/bush.kvox" "${KOZU_EXE}" voxelize "${KOZU_SOURCE_DIR}/scenes/meshes/bush.ply"
              --resolution 128 -o "${scenes}/volumes/bush.kvox")

if(KOZU_PYTHON)
  kozu_generate("${scenes}/showcase.glb" "${KOZU_PYTHON}" "${KOZU_SOURCE_DIR}/scripts/make-showcase-gltf.py" -o
                "${scenes}/showcase.glb")
else()
  message(WARNING "python3 was not found when kozu was configured, so ${scenes}/showcase.glb (read by "
                  "showcase/showcase.json) is not installed: install python3, reconfigure and install again")
endif()
