# Read by ctest (a TEST_INCLUDE_FILES entry, tests/CMakeLists.txt) where DELI_TEST_GROUPS is on:
# the test cases gtest_discover_tests found in one binary, registered as groups of at most
# `group_size` cases of one suite, each group one process (--gtest_filter listing its cases),
# instead of one process per case. Set before including: cases_file (the discovered cases,
# "<binary>[1]_tests.cmake"), group_size.
#
# Why: a process of a test binary built with AddressSanitizer costs about 0.2 s to start and
# leak-check at its exit (perf: the loader's relocations, ASan's registration of globals,
# page faults, LSan's scan), against about 10 ms without the sanitizers: over ~600 cases the
# sanitizer pass's tests took 295 s, and 205 s in groups of 16 (back to back, 2 cores,
# ctest -j2). A group runs its cases as the binary run alone runs them, in order in one
# process, so a case that depends on another's leftovers fails here too. A failing group's
# output names the failing case.
# The binary's name, for the tests that report a problem.
get_filename_component(cases_name "${cases_file}" NAME)
if(NOT EXISTS "${cases_file}")
  add_test("${cases_name}_NOT_BUILT" "${cases_name}_NOT_BUILT")
  return()
endif()

file(STRINGS "${cases_file}" lines)
set(suites "")
set(properties "")
set(discovered 0)
set(placed 0)
foreach(line IN LISTS lines)
  if(line MATCHES "^add_test\\(")
    math(EXPR discovered "${discovered} + 1")
  endif()
  if(line MATCHES "^add_test\\(\\[=\\[.*\\]=\\] +([^ ]+) \\[==\\[--gtest_filter=([^]]+)\\]==\\]")
    set(binary "${CMAKE_MATCH_1}")
    set(case "${CMAKE_MATCH_2}")
    if(case MATCHES "(^|\\.)DISABLED_")
      # Listed as disabled, as gtest_discover_tests lists it; never run.
      add_test("${case}" "${binary}" "--gtest_filter=${case}")
      set_tests_properties("${case}" PROPERTIES DISABLED TRUE)
      math(EXPR placed "${placed} + 1")
      continue()
    endif()
    string(FIND "${case}" "." dot)
    string(SUBSTRING "${case}" 0 ${dot} suite)
    # A list variable per suite; the suite's name may hold "/": hash it for the variable.
    string(MD5 key "${suite}")
    if(NOT DEFINED cases_${key})
      list(APPEND suites "${suite}")
      set(cases_${key} "")
    endif()
    list(APPEND cases_${key} "${case}")
    math(EXPR placed "${placed} + 1")
  elseif(properties STREQUAL "" AND line MATCHES "^set_tests_properties\\(\\[=\\[.*\\]=\\] +PROPERTIES (WORKING_DIRECTORY .*)\\)$")
    # Every case of a binary has the same properties (deli_test_binary). The skip expression
    # is left out: one skipped case would mark its whole group skipped. A group with a skipped
    # case passes, and its output shows the skip.
    string(REPLACE [=[SKIP_REGULAR_EXPRESSION [==[\[  SKIPPED \]]==] ]=] "" properties
                   "${CMAKE_MATCH_1}")
  endif()
endforeach()

# A case this file could not read (an unexpected line format) must not go unrun unseen.
if(NOT placed EQUAL discovered)
  add_test("${cases_name}: ${placed} of ${discovered} cases grouped, see cmake/test_groups.cmake"
           false)
endif()

foreach(suite IN LISTS suites)
  string(MD5 key "${suite}")
  list(LENGTH cases_${key} count)
  set(first 0)
  while(first LESS count)
    math(EXPR last "${first} + ${group_size} - 1")
    if(last GREATER_EQUAL count)
      math(EXPR last "${count} - 1")
    endif()
    set(group "")
    foreach(index RANGE ${first} ${last})
      list(GET cases_${key} ${index} case)
      list(APPEND group "${case}")
    endforeach()
    list(JOIN group ":" filter)
    if(count LESS_EQUAL group_size)
      set(name "${suite}")
    else()
      math(EXPR from "${first} + 1")
      math(EXPR to "${last} + 1")
      set(name "${suite}[${from}-${to}]")
    endif()
    add_test("${name}" "${binary}" "--gtest_filter=${filter}")
    cmake_language(EVAL CODE "set_tests_properties([==[${name}]==] PROPERTIES ${properties})")
    math(EXPR first "${last} + 1")
  endwhile()
endforeach()
