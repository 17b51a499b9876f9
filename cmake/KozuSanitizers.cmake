# KOZU_SANITIZE=ON builds everything with AddressSanitizer and UBSan.
# UBSan aborts on the first report so that a test fails instead of printing and passing.
if(KOZU_SANITIZE)
  set(_kozu_san -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_compile_options(${_kozu_san})
  add_link_options(${_kozu_san})
endif()
