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
  # A list value must be escaped to survive gtest_discover_tests' own argument parsing.
  string(REPLACE ";" "\\;" labels "unit;${ARG_LABELS}")
  # Listing a binary that loads PCL and OpenCV can take seconds on a loaded machine.
  gtest_discover_tests(${name} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS "${labels}" TIMEOUT 300)
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

# sarmap_add_bench(NAME SOURCES ... LIBS ... [GBENCH] [NETNS] [ARGS ...])
# A benchmark binary. `run_NAME` runs it alone; `bench` (make bench) runs all of them, one
# after another so that they do not share the two cores.
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
  add_custom_target(run_${name}
    COMMAND ${CMAKE_COMMAND} -E echo "=== ${name}"
    COMMAND ${CMAKE_COMMAND} -E env SARMAP_BIN_DIR=${CMAKE_BINARY_DIR}/bin ${cmd}
    DEPENDS ${name} USES_TERMINAL VERBATIM)
  set_property(GLOBAL APPEND PROPERTY SARMAP_BENCH_TARGETS ${name})
  set_property(GLOBAL PROPERTY SARMAP_BENCH_CMD_${name} ${cmd})
endfunction()

function(sarmap_finalize_bench_target)
  get_property(names GLOBAL PROPERTY SARMAP_BENCH_TARGETS)
  set(commands "")
  foreach(name ${names})
    get_property(cmd GLOBAL PROPERTY SARMAP_BENCH_CMD_${name})
    list(APPEND commands COMMAND ${CMAKE_COMMAND} -E echo "=== ${name}"
                         COMMAND ${CMAKE_COMMAND} -E env SARMAP_BIN_DIR=${CMAKE_BINARY_DIR}/bin ${cmd})
  endforeach()
  add_custom_target(bench ${commands} USES_TERMINAL VERBATIM)
  if(names)
    add_dependencies(bench ${names})
  endif()
endfunction()
