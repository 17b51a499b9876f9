# The layering check (ctest: test_layers). The folders of src/, apps/ and python/ form a strict stack, each including
# only folders below it (to its left here); core is the ground floor. A folder may include itself. An include of
# a folder above, or of an unknown folder, fails the test and names the file, the line and the rule.
#   cmake -DKOZU_SOURCE_DIR=<repo> -P tests/layers/check_layers.cmake
# The sibling model folders (bssrdf, media, lights, materials) are ordered too, so no loop can form among them.
cmake_policy(SET CMP0057 NEW)  # if(... IN_LIST ...) in script mode
set(KOZU_LAYERS core io geometry textures bssrdf media lights materials scene integrators render tools apps python)
# Pairs the stack allows but the design does not, as "from>to": the materials do not include the lights (what both
# need, like the LTC distribution, lives below both: core/ltc.h; the fitted tables are the materials' own).
# The Python module and the command are siblings on top: each calls the library, neither the other.
set(KOZU_FORBIDDEN "materials>lights" "python>apps")

if(NOT KOZU_SOURCE_DIR)
  message(FATAL_ERROR "check_layers.cmake: set -DKOZU_SOURCE_DIR")
endif()
file(GLOB_RECURSE sources RELATIVE ${KOZU_SOURCE_DIR}
  ${KOZU_SOURCE_DIR}/src/*.h ${KOZU_SOURCE_DIR}/src/*.cpp ${KOZU_SOURCE_DIR}/src/*.inc ${KOZU_SOURCE_DIR}/src/*.in
  ${KOZU_SOURCE_DIR}/apps/*.h ${KOZU_SOURCE_DIR}/apps/*.cpp ${KOZU_SOURCE_DIR}/python/*.h ${KOZU_SOURCE_DIR}/python/*.cpp)
set(violations 0)
set(files 0)
set(includes 0)
foreach(rel IN LISTS sources)
  if(rel MATCHES "^src/([^/]+)/")
    set(folder ${CMAKE_MATCH_1})
  elseif(rel MATCHES "^apps/")
    set(folder apps)
  elseif(rel MATCHES "^python/")
    set(folder python)
  else()
    message(SEND_ERROR "${rel}: a file outside the layer folders")
    math(EXPR violations "${violations} + 1")
    continue()
  endif()
  list(FIND KOZU_LAYERS ${folder} level)
  if(level LESS 0)
    message(SEND_ERROR "${rel}: folder '${folder}' is not in the layer list of tests/layers/check_layers.cmake")
    math(EXPR violations "${violations} + 1")
    continue()
  endif()
  math(EXPR files "${files} + 1")
  file(STRINGS ${KOZU_SOURCE_DIR}/${rel} lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
  foreach(line IN LISTS lines)
    if(NOT line MATCHES "#[ \t]*include[ \t]*\"([^\"/]+)/")
      continue()  # same-folder includes without a folder ("x.inc") stay on the floor
    endif()
    set(target ${CMAKE_MATCH_1})
    math(EXPR includes "${includes} + 1")
    list(FIND KOZU_LAYERS ${target} target_level)
    if(target_level LESS 0)
      message(SEND_ERROR "${rel}: ${line}: '${target}' is not a layer folder")
      math(EXPR violations "${violations} + 1")
    elseif("${folder}>${target}" IN_LIST KOZU_FORBIDDEN)
      message(SEND_ERROR "${rel}: ${line}: '${folder}' may not include '${target}' (KOZU_FORBIDDEN)")
      math(EXPR violations "${violations} + 1")
    elseif(target_level GREATER level)
      message(SEND_ERROR "${rel}: ${line}: '${folder}' may not include '${target}', a floor above it "
                         "(layers, bottom up: ${KOZU_LAYERS})")
      math(EXPR violations "${violations} + 1")
    endif()
  endforeach()
endforeach()
if(files EQUAL 0 OR includes EQUAL 0)
  message(FATAL_ERROR "check_layers: no sources or includes found under ${KOZU_SOURCE_DIR} (wrong directory?)")
endif()
if(violations GREATER 0)
  message(FATAL_ERROR "check_layers: ${violations} include(s) go up the stack")
endif()
message(STATUS "check_layers: ${files} files, ${includes} includes between layer folders or within one, none goes up")
