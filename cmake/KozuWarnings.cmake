# Warnings on for every kozu target; third-party headers are included as SYSTEM.
function(kozu_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local
                         -Wno-missing-field-initializers)
endfunction()
