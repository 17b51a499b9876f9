# KOZU_SANITIZE=ON builds everything with AddressSanitizer and UBSan.
# UBSan aborts on the first report so that a test fails instead of printing and passing.
if(KOZU_SANITIZE)
  set(_kozu_san -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  # -O1 -g1 (after the build type's flags, so they win): ASan's recommended level and line tables, enough for
  # reports with file:line; it halves the sanitizer build's compile time (CI: 2 cores, 30 minutes).
  add_compile_options(${_kozu_san} -O1 -g1)
  # clang: checks left out in third-party headers, each with its reason.
  add_compile_options($<$<CXX_COMPILER_ID:Clang>:-fsanitize-ignorelist=${PROJECT_SOURCE_DIR}/cmake/ubsan_ignorelist.txt>)
  add_link_options(${_kozu_san})
endif()

# KOZU_FUZZ=ON (clang only, with KOZU_SANITIZE) builds the libFuzzer targets of tests/fuzz too (scripts/test.sh:
# in build-asan, beside the sanitizer tests). Only the sources that read untrusted input are instrumented for
# coverage (kozu_fuzz_instrument); the tests run those parsers instrumented, which costs them nothing measurable.
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
    # clang refuses a precompiled header built without the instrumentation, so these files parse their headers.
    set_source_files_properties(${ARGN} DIRECTORY ${PROJECT_SOURCE_DIR} PROPERTIES COMPILE_OPTIONS
                                -fsanitize=fuzzer-no-link SKIP_PRECOMPILE_HEADERS ON)
  endif()
endfunction()
