# Helpers shared by all components.

set(SARMAP_NETNS ${PROJECT_SOURCE_DIR}/tests/harness/sarmap-netns CACHE INTERNAL "")
set(SARMAP_DATA_DIR ${PROJECT_SOURCE_DIR}/../shared/data CACHE PATH "Real test data (shared/data)")
# The tests' scratch files (::testing::TempDir(): gtest reads TEST_TMPDIR) go below
# build/test-tmp, which the fixture sarmap_test_tmp empties at the start of every ctest run that
# runs a test needing it: a test run leaves nothing in /tmp, and a build never holds more than
# one run's files.
set(SARMAP_TEST_TMPDIR ${CMAKE_BINARY_DIR}/test-tmp CACHE INTERNAL "")

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
    PROPERTIES LABELS "${labels}" TIMEOUT 300 ENVIRONMENT "TEST_TMPDIR=${SARMAP_TEST_TMPDIR}"
               FIXTURES_REQUIRED sarmap_test_tmp)
endfunction()

# sarmap_use_test_tmpdir(TEST...): a test added with add_test writes its scratch files below
# SARMAP_TEST_TMPDIR too (sarmap_add_gtest and sarmap_add_netns_test do it for theirs).
function(sarmap_use_test_tmpdir)
  foreach(test ${ARGN})
    set_property(TEST ${test} APPEND PROPERTY ENVIRONMENT "TEST_TMPDIR=${SARMAP_TEST_TMPDIR}")
    set_property(TEST ${test} APPEND PROPERTY FIXTURES_REQUIRED sarmap_test_tmp)
  endforeach()
endfunction()

# The fixture: SARMAP_TEST_TMPDIR emptied before the tests that need it.
function(sarmap_add_test_tmp_fixture)
  add_test(NAME sarmap_test_tmp_reset
    COMMAND sh -c "rm -rf \"$1\" && mkdir -p \"$1\"" sh ${SARMAP_TEST_TMPDIR})
  set_tests_properties(sarmap_test_tmp_reset PROPERTIES FIXTURES_SETUP sarmap_test_tmp
                       LABELS unit)
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
    ENVIRONMENT "SARMAP_BIN_DIR=${CMAKE_BINARY_DIR}/bin;SARMAP_SOURCE_DIR=${PROJECT_SOURCE_DIR};SARMAP_DATA_DIR=${SARMAP_DATA_DIR};TEST_TMPDIR=${SARMAP_TEST_TMPDIR}"
    FIXTURES_REQUIRED sarmap_test_tmp)
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

# sarmap_core_library(TARGET)
# Marks a library as an algorithm core: it must not link LCM, the message types or the node
# runtime. sarmap_finalize_core_check() writes each core's link closure and archive, and the
# test core_libraries_link_no_lcm checks both (tests/check_core_links.py).
function(sarmap_core_library name)
  set_property(GLOBAL APPEND PROPERTY SARMAP_CORE_LIBRARIES ${name})
endfunction()

# The libraries `target` links, directly or through other targets (usage requirements only:
# what a program linking `target` ends up linking).
function(_sarmap_link_closure target out_var)
  set(seen "")
  set(queue ${target})
  while(queue)
    list(POP_FRONT queue current)
    if(current IN_LIST seen)
      continue()
    endif()
    list(APPEND seen ${current})
    if(NOT TARGET ${current})
      continue()
    endif()
    get_target_property(type ${current} TYPE)
    set(deps "")
    if(NOT type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(direct ${current} LINK_LIBRARIES)
      if(direct)
        list(APPEND deps ${direct})
      endif()
    endif()
    get_target_property(iface ${current} INTERFACE_LINK_LIBRARIES)
    if(iface)
      list(APPEND deps ${iface})
    endif()
    foreach(dep ${deps})
      # $<LINK_ONLY:x> (a static library's private dependency) is still linked.
      string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" dep "${dep}")
      if(NOT dep MATCHES "^\\$<")
        list(APPEND queue ${dep})
      endif()
    endforeach()
  endwhile()
  list(REMOVE_AT seen 0)
  set(${out_var} ${seen} PARENT_SCOPE)
endfunction()

function(sarmap_finalize_core_check)
  get_property(names GLOBAL PROPERTY SARMAP_CORE_LIBRARIES)
  set(lines "")
  set(files "")
  foreach(name ${names})
    _sarmap_link_closure(${name} closure)
    string(REPLACE ";" " " closure_text "${closure}")
    string(APPEND lines "${name}\t$<TARGET_FILE:${name}>\t${closure_text}\n")
    list(APPEND files $<TARGET_FILE:${name}>)
  endforeach()
  file(GENERATE OUTPUT ${CMAKE_BINARY_DIR}/core_libraries.tsv CONTENT "${lines}")
  add_test(NAME core_libraries_link_no_lcm
    COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/check_core_links.py
            ${CMAKE_BINARY_DIR}/core_libraries.tsv)
  set_tests_properties(core_libraries_link_no_lcm PROPERTIES LABELS unit)
  # The check itself: the LCM runtime, listed as if it were a core, must fail it.
  _sarmap_link_closure(sarmap_runtime closure)
  string(REPLACE ";" " " closure_text "${closure}")
  file(GENERATE OUTPUT ${CMAKE_BINARY_DIR}/core_libraries_selftest.tsv
    CONTENT "sarmap_runtime\t$<TARGET_FILE:sarmap_runtime>\t${closure_text}\n")
  add_test(NAME core_libraries_check_catches_lcm
    COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/check_core_links.py
            ${CMAKE_BINARY_DIR}/core_libraries_selftest.tsv)
  set_tests_properties(core_libraries_check_catches_lcm PROPERTIES LABELS unit WILL_FAIL TRUE)
endfunction()
