# Writes CTEST_FILE: one CTest test per GoogleTest suite of TEST_EXECUTABLE,
# named as the suite and running `TEST_EXECUTABLE --gtest_filter=SUITE.*`.
# The tests of a suite share one process: a test binary linked with LibTorch
# spends about 0.7 s loading it before its first test, longer than most unit
# tests take. Each test is registered through flowplan_suite_test(NAME COMMAND...),
# which the file including CTEST_FILE defines (tests/CMakeLists.txt). Run in
# script mode after the binary is built:
#   cmake -DTEST_EXECUTABLE=<binary> -DCTEST_FILE=<file> -DDISCOVERY_TIMEOUT=<s> -P gtest_suites.cmake
execute_process(COMMAND "${TEST_EXECUTABLE}" --gtest_list_tests
                OUTPUT_VARIABLE listing ERROR_VARIABLE errors RESULT_VARIABLE status
                TIMEOUT ${DISCOVERY_TIMEOUT})
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${TEST_EXECUTABLE} --gtest_list_tests failed (${status}): ${errors}${listing}")
endif()
# A suite's line starts in the first column and ends its name with a dot ("Suite." or
# "Instance/Suite.  # TypeParam = ..."); its tests' lines are indented.
string(REGEX MATCHALL "(^|\n)[^ \n#][^ \n]*\\." suite_lines "${listing}")
set(content "# Written by cmake/gtest_suites.cmake from ${TEST_EXECUTABLE} --gtest_list_tests.\n")
set(count 0)
foreach(line IN LISTS suite_lines)
  string(STRIP "${line}" suite)
  string(REGEX REPLACE "\\.$" "" suite "${suite}")
  if(suite MATCHES "^DISABLED_")
    continue()
  endif()
  string(APPEND content "flowplan_suite_test([==[${suite}]==] [==[${TEST_EXECUTABLE}]==] [==[--gtest_filter=${suite}.*]==])\n")
  math(EXPR count "${count} + 1")
endforeach()
if(count EQUAL 0)
  message(FATAL_ERROR "${TEST_EXECUTABLE} --gtest_list_tests lists no suite:\n${listing}")
endif()
# Written whole, then moved into place: an interrupted build leaves the previous file or none.
file(WRITE "${CTEST_FILE}.part" "${content}")
file(RENAME "${CTEST_FILE}.part" "${CTEST_FILE}")
