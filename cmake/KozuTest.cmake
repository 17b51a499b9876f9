# kozu_add_test(NAME name LABEL unit|stat SOURCES ...): one GoogleTest binary,
# each of its tests registered with ctest under the given label.
include(GoogleTest)
function(kozu_add_test)
  cmake_parse_arguments(T "" "NAME;LABEL" "SOURCES" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES})
  target_link_libraries(${T_NAME} PRIVATE kozu_core kozu_test_support GTest::gtest GTest::gtest_main)
  kozu_set_warnings(${T_NAME})
  gtest_discover_tests(${T_NAME} PROPERTIES LABELS ${T_LABEL} DISCOVERY_TIMEOUT 60)
endfunction()
