# Helpers shared by all components.

set(SARMAP_NETNS ${PROJECT_SOURCE_DIR}/tests/harness/sarmap-netns CACHE INTERNAL "")
set(SARMAP_DATA_DIR ${PROJECT_SOURCE_DIR}/../shared/data CACHE PATH "Real test data (shared/data)")

# sarmap_add_gtest(NAME SOURCES a.cc b.cc LIBS x y [LABELS l])
# One test binary; its cases are discovered at test time so CTest lists each one.
function(sarmap_add_gtest name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main GTest::gmock)
  target_compile_definitions(${name} PRIVATE
    SARMAP_DATA_DIR="${SARMAP_DATA_DIR}" SARMAP_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    SARMAP_BIN_DIR="${CMAKE_BINARY_DIR}/bin")
  gtest_discover_tests(${name} DISCOVERY_MODE PRE_TEST
    PROPERTIES LABELS "unit;${ARG_LABELS}" TIMEOUT 300)
endfunction()

# sarmap_add_netns_test(NAME COMMAND cmd args... [TIMEOUT s])
# A multi-process test: runs COMMAND inside a private network namespace (loopback only,
# multicast routed on lo) so it uses real UDP multicast and never touches a real network.
function(sarmap_add_netns_test name)
  cmake_parse_arguments(ARG "" "TIMEOUT" "COMMAND" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  add_test(NAME ${name} COMMAND ${SARMAP_NETNS} ${ARG_COMMAND})
  set_tests_properties(${name} PROPERTIES LABELS "multiprocess" TIMEOUT ${ARG_TIMEOUT}
    ENVIRONMENT "SARMAP_BIN_DIR=${CMAKE_BINARY_DIR}/bin;SARMAP_SOURCE_DIR=${PROJECT_SOURCE_DIR};SARMAP_DATA_DIR=${SARMAP_DATA_DIR}")
endfunction()

# sarmap_add_bench(NAME SOURCES ... LIBS ... [NETNS] [ARGS ...])
# A benchmark binary; `make bench` (the `bench` target) builds and runs all of them.
function(sarmap_add_bench name)
  cmake_parse_arguments(ARG "NETNS;GBENCH" "" "SOURCES;LIBS;ARGS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS})
  target_compile_definitions(${name} PRIVATE
    SARMAP_DATA_DIR="${SARMAP_DATA_DIR}" SARMAP_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    SARMAP_BIN_DIR="${CMAKE_BINARY_DIR}/bin")
  if(ARG_GBENCH)
    target_link_libraries(${name} PRIVATE benchmark::benchmark benchmark::benchmark_main)
  endif()
  set(cmd $<TARGET_FILE:${name}> ${ARG_ARGS})
  if(ARG_NETNS)
    set(cmd ${SARMAP_NETNS} ${cmd})
  endif()
  set_property(GLOBAL APPEND PROPERTY SARMAP_BENCH_TARGETS ${name})
  add_custom_target(run_${name}
    COMMAND ${CMAKE_COMMAND} -E echo "=== ${name}"
    COMMAND ${CMAKE_COMMAND} -E env SARMAP_BIN_DIR=${CMAKE_BINARY_DIR}/bin ${cmd}
    DEPENDS ${name} USES_TERMINAL VERBATIM)
  set_property(GLOBAL APPEND PROPERTY SARMAP_BENCH_RUNS run_${name})
endfunction()

function(sarmap_finalize_bench_target)
  get_property(runs GLOBAL PROPERTY SARMAP_BENCH_RUNS)
  add_custom_target(bench)
  # Run one after another: benchmarks must not share the two cores with each other.
  set(prev "")
  foreach(r ${runs})
    if(prev)
      add_dependencies(${r} ${prev})
    endif()
    set(prev ${r})
  endforeach()
  if(prev)
    add_dependencies(bench ${prev})
  endif()
endfunction()
