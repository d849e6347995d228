# How long tests may take: FACT_TEST_TIME_SCALE (a whole number >= 1, default 1, or the environment
# variable of the same name at configure time) multiplies every test's TIMEOUT, and ctest hands it
# to every test as the environment variable FACT_TEST_TIME_SCALE, which multiplies the tests' own
# "give up waiting after X s" deadlines (C++: test/test_time.h; shell: test/lib.sh). Under qemu
# (scripts/cross-build-arm64.sh) it is 10. It never changes what a test checks, only how long it waits.
set(_fact_scale_default 1)
if(DEFINED ENV{FACT_TEST_TIME_SCALE} AND NOT "$ENV{FACT_TEST_TIME_SCALE}" STREQUAL "")
  set(_fact_scale_default "$ENV{FACT_TEST_TIME_SCALE}")
endif()
set(FACT_TEST_TIME_SCALE "${_fact_scale_default}" CACHE STRING
  "Multiplies test timeouts and the tests' waiting deadlines (10 under qemu)")
if(NOT FACT_TEST_TIME_SCALE MATCHES "^[1-9][0-9]*$")
  message(FATAL_ERROR "FACT_TEST_TIME_SCALE='${FACT_TEST_TIME_SCALE}' is not a whole number >= 1")
endif()
set(FACT_TEST_ENVIRONMENT "FACT_TEST_TIME_SCALE=${FACT_TEST_TIME_SCALE}")

# fact_discover_tests(TARGET [TIMEOUT_SECONDS]): gtest_discover_tests with the timeout (seconds at
# native speed; none: ctest's default) and the discovery timeout (30 s) scaled.
function(fact_discover_tests target)
  math(EXPR discovery "30 * ${FACT_TEST_TIME_SCALE}")
  set(properties ENVIRONMENT "${FACT_TEST_ENVIRONMENT}")
  if(ARGC GREATER 1)
    math(EXPR timeout "${ARGV1} * ${FACT_TEST_TIME_SCALE}")
    list(APPEND properties TIMEOUT ${timeout})
  endif()
  gtest_discover_tests(${target} DISCOVERY_TIMEOUT ${discovery} PROPERTIES ${properties})
endfunction()

# fact_scale_test_timeouts(): the add_test tests of the calling directory get their TIMEOUT scaled
# and the environment variable. Called once, at the end of test/CMakeLists.txt.
function(fact_scale_test_timeouts)
  get_property(tests DIRECTORY PROPERTY TESTS)
  foreach(t IN LISTS tests)
    get_test_property(${t} TIMEOUT timeout)
    if(timeout)
      math(EXPR timeout "${timeout} * ${FACT_TEST_TIME_SCALE}")
      set_tests_properties(${t} PROPERTIES TIMEOUT ${timeout})
    endif()
    set_tests_properties(${t} PROPERTIES ENVIRONMENT "${FACT_TEST_ENVIRONMENT}")
  endforeach()
endfunction()
