# pz_cc_library(NAME name SRCS ... [HDRS ...] DEPS ...)  -> target pz_<name>, alias pz::<name>
# pz_cc_test(NAME name SRCS ... DEPS ... [LABELS ...])  -> gtest executable registered with ctest
include_guard(GLOBAL)

function(pz_cc_library)
  cmake_parse_arguments(PZ "" "NAME" "SRCS;HDRS;DEPS;PUBLIC_DEFS" ${ARGN})
  set(_t pz_${PZ_NAME})
  if(PZ_SRCS)
    add_library(${_t} STATIC ${PZ_SRCS} ${PZ_HDRS})
    target_include_directories(${_t} PUBLIC ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR})
    target_link_libraries(${_t} PUBLIC ${PZ_DEPS})
    target_compile_definitions(${_t} PUBLIC ${PZ_PUBLIC_DEFS})
  else()
    add_library(${_t} INTERFACE)
    target_include_directories(${_t} INTERFACE ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR})
    target_link_libraries(${_t} INTERFACE ${PZ_DEPS})
  endif()
  add_library(pz::${PZ_NAME} ALIAS ${_t})
endfunction()

function(pz_cc_test)
  cmake_parse_arguments(PZ "" "NAME;TIMEOUT" "SRCS;DEPS;LABELS" ${ARGN})
  set(_t ${PZ_NAME})
  add_executable(${_t} ${PZ_SRCS})
  target_link_libraries(${_t} PRIVATE ${PZ_DEPS} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${_t} PRIVATE
    PIEZOID_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data"
    PIEZOID_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
  add_test(NAME ${_t} COMMAND ${_t})
  if(NOT PZ_TIMEOUT)
    set(PZ_TIMEOUT 300)
  endif()
  set_tests_properties(${_t} PROPERTIES TIMEOUT ${PZ_TIMEOUT} LABELS "${PZ_LABELS}")
endfunction()
