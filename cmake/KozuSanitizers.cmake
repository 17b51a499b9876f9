# KOZU_SANITIZE=ON builds everything with AddressSanitizer and UBSan.
# UBSan aborts on the first report so that a test fails instead of printing and passing.
if(KOZU_SANITIZE)
  set(_kozu_san -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  # -O1 -g1 (after the build type's flags, so they win): ASan's recommended level and line tables, enough for
  # reports with file:line; it halves the sanitizer build's compile time (CI: 2 cores, 30 minutes).
  add_compile_options(${_kozu_san} -O1 -g1)
  add_link_options(${_kozu_san})
endif()

# KOZU_FUZZ=ON (clang only, with KOZU_SANITIZE) builds the libFuzzer targets of tests/fuzz, in a build of their
# own (scripts/test.sh: build-fuzz). Only the sources that read untrusted input are instrumented for coverage
# (kozu_fuzz_instrument).
if(KOZU_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "KOZU_FUZZ needs clang (libFuzzer): configure with CC=clang CXX=clang++")
  endif()
  if(NOT KOZU_SANITIZE)
    message(FATAL_ERROR "KOZU_FUZZ needs KOZU_SANITIZE=ON (findings are sanitizer reports)")
  endif()
endif()
function(kozu_fuzz_instrument)
  if(KOZU_FUZZ)
    set_source_files_properties(${ARGN} DIRECTORY ${PROJECT_SOURCE_DIR} PROPERTIES COMPILE_OPTIONS
                                -fsanitize=fuzzer-no-link)
  endif()
endfunction()
