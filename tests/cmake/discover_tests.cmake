# Included by CTest (tests/CMakeLists.txt's include files) when a test executable is newer than its
# list: lists the executable's doctest test cases and writes a CTest file that registers each one as its own test, so CTest lists, times and reports
# every case (a case that skips exits with 77, at::test::skipf, and is reported as skipped).
#
# Inputs (variables): TEST_EXECUTABLE, TEST_WORKING_DIR, TEST_PREFIX (the test names start "<prefix>: "), TEST_LABEL (the
# module's label), TEST_EXTRA_ARG (one argument or empty), TEST_TIMEOUT (seconds),
# TEST_ENVIRONMENT (NAME=VALUE entries separated by '|'), TEST_FIXTURES (fixture names separated
# by '|'), TEST_ALL_SLOW (ON: every case is labelled `slow`), SLOW_LIST (file of the test sources
# and cases labelled `slow`), CTEST_FILE (output).

if(NOT EXISTS "${TEST_EXECUTABLE}")
  message(FATAL_ERROR "discover_tests: '${TEST_EXECUTABLE}' does not exist")
endif()
execute_process(
  COMMAND "${TEST_EXECUTABLE}" --list-test-cases --reporters=xml
  OUTPUT_VARIABLE listing
  RESULT_VARIABLE status
  WORKING_DIRECTORY "${TEST_WORKING_DIR}")
if(NOT status EQUAL 0)
  message(FATAL_ERROR "discover_tests: '${TEST_EXECUTABLE} --list-test-cases' failed (${status}):\n${listing}")
endif()

# The slow list: lines "SOURCE" (every case of the test sources matching that glob, relative to
# tests/: '*' matches within a folder) or "SOURCE :: CASE NAME" (one case); '#' starts a comment.
set(slow_sources "")
set(slow_cases "")
if(EXISTS "${SLOW_LIST}")
  file(STRINGS "${SLOW_LIST}" slow_lines)
  foreach(line IN LISTS slow_lines)
    string(STRIP "${line}" line)
    if(NOT line OR line MATCHES "^#")
      continue()
    endif()
    string(FIND "${line}" " :: " sep)
    if(sep EQUAL -1)
      string(REGEX REPLACE "([.+?^$()])" "\\\\\\1" pattern "${line}")
      string(REPLACE "*" "[^/]*" pattern "${pattern}")
      list(APPEND slow_sources "^${pattern}$")
    else()
      string(REPLACE ";" "," line "${line}")  # a case name with ';' would split the list
      list(APPEND slow_cases "${line}")
    endif()
  endforeach()
endif()

# A value as a CMake bracket argument, whatever characters it holds.
function(bracketed out value)
  set(${out} "[==[${value}]==]" PARENT_SCOPE)
endfunction()

function(xml_unescape out value)
  string(REPLACE "&quot;" "\"" value "${value}")
  string(REPLACE "&apos;" "'" value "${value}")
  string(REPLACE "&lt;" "<" value "${value}")
  string(REPLACE "&gt;" ">" value "${value}")
  string(REPLACE "&amp;" "&" value "${value}")
  set(${out} "${value}" PARENT_SCOPE)
endfunction()

set(script "")
# Case names may hold ';', CMake's list separator: it travels as the token @SEMICOLON@ until written out.
string(REPLACE ";" "@SEMICOLON@" listing "${listing}")
string(REGEX MATCHALL "<TestCase name=\"[^\"]*\" filename=\"[^\"]*\"" cases "${listing}")
foreach(entry IN LISTS cases)
  string(REGEX REPLACE "^<TestCase name=\"([^\"]*)\" filename=\"([^\"]*)\"$" "\\1" name "${entry}")
  string(REGEX REPLACE "^<TestCase name=\"([^\"]*)\" filename=\"([^\"]*)\"$" "\\2" file "${entry}")
  xml_unescape(name "${name}")
  string(REPLACE "@SEMICOLON@" ";" name "${name}")
  xml_unescape(file "${file}")
  # doctest reads ',' in a filter as a separator; '\,' is a literal comma.
  string(REPLACE "," "\\," filter "${name}")
  string(REGEX REPLACE "^.*tests/" "" source "${file}")
  set(labels "${TEST_LABEL}")
  string(REPLACE ";" "," case_key "${source} :: ${name}")
  set(slow ${TEST_ALL_SLOW})
  foreach(pattern IN LISTS slow_sources)
    if(source MATCHES "${pattern}")
      set(slow ON)
    endif()
  endforeach()
  list(FIND slow_cases "${case_key}" listed)  # list(FIND), not IN_LIST: CTest reads this without a policy version
  if(NOT listed EQUAL -1)
    set(slow ON)
  endif()
  if(slow)
    list(APPEND labels slow)
  else()
    list(APPEND labels fast)
  endif()
  bracketed(test_name "${TEST_PREFIX}: ${name}")
  bracketed(exe "${TEST_EXECUTABLE}")
  bracketed(filter_arg "--test-case=${filter}")
  set(args "")
  if(NOT "${TEST_EXTRA_ARG}" STREQUAL "")
    bracketed(q "${TEST_EXTRA_ARG}")
    set(args " ${q}")
  endif()
  set(props " TIMEOUT ${TEST_TIMEOUT}")
  if(NOT "${TEST_ENVIRONMENT}" STREQUAL "")
    string(REPLACE "|" ";" env "${TEST_ENVIRONMENT}")
    string(APPEND props " ENVIRONMENT [==[${env}]==]")
  endif()
  if(NOT "${TEST_FIXTURES}" STREQUAL "")
    string(REPLACE "|" ";" fixtures "${TEST_FIXTURES}")
    string(APPEND props " FIXTURES_REQUIRED [==[${fixtures}]==]")
  endif()
  set(labels_value "${labels}")
  bracketed(labels_arg "${labels_value}")
  bracketed(wd "${TEST_WORKING_DIR}")
  string(APPEND script "add_test(${test_name} ${exe} ${filter_arg}${args})\n")
  string(APPEND script "set_tests_properties(${test_name} PROPERTIES WORKING_DIRECTORY ${wd} LABELS ${labels_arg}"
                       " SKIP_RETURN_CODE 77${props})\n")
endforeach()
if(NOT cases)
  message(FATAL_ERROR "discover_tests: '${TEST_EXECUTABLE}' lists no test cases")
endif()
file(WRITE "${CTEST_FILE}" "${script}")
