# Small helpers so each module's CMakeLists.txt stays a few lines.
#
# gf_add_library(NAME
#                [SOURCES a.cc b.cc ...]
#                [PUBLIC_LIBS ...] [PRIVATE_LIBS ...])
#   Builds library gf_<NAME> (alias gf::<NAME>) from the module folder. The include root is the
#   repository root, so headers are included as "acquisition/camera.h". A module with no sources yet
#   becomes an INTERFACE library that only carries its dependencies.
#
# gf_add_test(MODULE NAME SOURCES a_test.cc ... [LIBS ...] [TIMEOUT seconds] [LABEL label])
#   Builds a GoogleTest executable and registers its tests as MODULE/NAME so that
#   `ctest -R MODULE/` runs one module. Each test times out after TIMEOUT seconds (900). Its ctest
#   label is MODULE, or LABEL (`tests`: an end-to-end run, which `make sanitize` leaves out: the
#   sanitizer build does not build it). The other test executables are the dependencies of the
#   target gf_unit_tests, which `make sanitize` builds instead of everything.

function(gf_add_library NAME)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  set(target gf_${NAME})
  if(ARG_SOURCES)
    add_library(${target} STATIC ${ARG_SOURCES})
    target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
    target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_LIBS} PRIVATE ${ARG_PRIVATE_LIBS})
    target_compile_features(${target} PUBLIC cxx_std_17)
    target_compile_options(${target} PRIVATE ${GF_WARNING_FLAGS})
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR})
    target_link_libraries(${target} INTERFACE ${ARG_PUBLIC_LIBS})
  endif()
  add_library(gf::${NAME} ALIAS ${target})
endfunction()

# gf_add_benchmark(MODULE NAME SOURCES a_benchmark.cc ... [LIBS ...])
#   A Google Benchmark executable MODULE_NAME, built when GF_BUILD_BENCHMARKS is ON.
function(gf_add_benchmark MODULE NAME)
  if(NOT GF_BUILD_BENCHMARKS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  set(target ${MODULE}_${NAME})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_LIBS} benchmark::benchmark)
  target_compile_definitions(${target} PRIVATE GF_SHARED_DATASETS="${GF_SHARED_DATASETS}")
endfunction()

function(gf_add_test MODULE NAME)
  if(NOT GF_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "TIMEOUT;LABEL" "SOURCES;LIBS" ${ARGN})
  set(label ${MODULE})
  if(ARG_LABEL)
    set(label ${ARG_LABEL})
  endif()
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 900)
  endif()
  if(GF_SANITIZE AND label STREQUAL "tests")
    return()
  endif()
  set(target ${MODULE}_${NAME})
  if(NOT label STREQUAL "tests")
    set_property(GLOBAL APPEND PROPERTY GF_UNIT_TEST_TARGETS ${target})
  endif()
  if(GF_TSAN)
    list(APPEND ARG_SOURCES "${PROJECT_SOURCE_DIR}/tests/tsan_serial_opencv.cc")
  endif()
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main)
  target_compile_options(${target} PRIVATE ${GF_WARNING_FLAGS})
  # Tests find optional real data through this path and GTEST_SKIP() when it is absent.
  target_compile_definitions(${target} PRIVATE
    GF_SHARED_DATASETS="${GF_SHARED_DATASETS}"
    GF_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  gtest_discover_tests(${target}
    TEST_PREFIX "${MODULE}/${NAME}."
    DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS ${label} TIMEOUT ${ARG_TIMEOUT})
endfunction()
