# Precompiled headers. Parsing the standard library, glm, fmt, nlohmann-json (and GoogleTest in tests) is about
# half of a typical file's compile time; each is parsed once per build instead of once per file, which CI needs
# (two full builds on 2 cores in 30 minutes). kozu_core builds the header for the renderer's targets and
# kozu_test_support the one for the tests (with GoogleTest); the others reuse them. KOZU_PCH=OFF builds without,
# which is how a missing #include shows.
option(KOZU_PCH "Precompile the common third-party and standard headers" ON)
set(KOZU_PCH_HEADERS
  <algorithm> <array> <atomic> <chrono> <cmath> <cstdint> <cstring> <filesystem> <fstream> <functional> <limits>
  <memory> <mutex> <optional> <span> <stdexcept> <string> <string_view> <type_traits> <vector>
  <fmt/format.h> <glm/glm.hpp> <nlohmann/json.hpp>)

# kozu_precompile(TARGET [HEADERS ...]): TARGET compiles the common headers (plus HEADERS) once.
function(kozu_precompile target)
  if(KOZU_PCH)
    target_precompile_headers(${target} PRIVATE ${KOZU_PCH_HEADERS} ${ARGN})
  endif()
endfunction()

# kozu_reuse_pch(TARGET FROM): TARGET uses FROM's precompiled header (the same compile flags).
function(kozu_reuse_pch target from)
  if(KOZU_PCH)
    target_precompile_headers(${target} REUSE_FROM ${from})
  endif()
endfunction()
