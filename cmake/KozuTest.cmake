# kozu_add_test(NAME name LABEL unit|stat|integration [LOCK resource] SOURCES ...): one GoogleTest binary, each of its
# tests registered with ctest under the given label (or, with KOZU_TEST_PER_BINARY, the whole binary as one ctest
# entry); tests holding the same LOCK never run at the same time.
include(GoogleTest)
function(kozu_add_test)
  cmake_parse_arguments(T "" "NAME;LABEL;LOCK" "SOURCES" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES})
  target_link_libraries(${T_NAME} PRIVATE kozu_core kozu_test_support GTest::gtest GTest::gtest_main)
  kozu_set_warnings(${T_NAME})
  kozu_reuse_pch(${T_NAME} kozu_test_support)
  if(KOZU_TEST_PER_BINARY)
    # One ctest entry per binary: its tests share one process, which saves the start-up of a process per test
    # (loading OpenImageIO's 263 libraries costs 0.3-0.6 s, 1 s under the sanitizers: 80 % of a per-test run).
    add_test(NAME ${T_NAME} COMMAND ${T_NAME})
    set_tests_properties(${T_NAME} PROPERTIES LABELS ${T_LABEL})
    if(T_LOCK)
      set_tests_properties(${T_NAME} PROPERTIES RESOURCE_LOCK ${T_LOCK})
    endif()
  else()
    set(lock)
    if(T_LOCK)
      set(lock RESOURCE_LOCK ${T_LOCK})
    endif()
    gtest_discover_tests(${T_NAME} PROPERTIES LABELS ${T_LABEL} ${lock} DISCOVERY_TIMEOUT 60)
  endif()
endfunction()
