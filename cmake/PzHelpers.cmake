# The floors (cmake/floors.txt) made real in the build. Each folder's library exposes only its own
# folder: its PUBLIC include directory is <build>/include/<folder>, holding one link <folder> to
# the source folder, so "x/..." resolves only in a target that links pz::x (directly or through a
# PUBLIC dependency). A target may link only what its folder's line of cmake/floors.txt names.
#
# pz_cc_library(NAME name SRCS ... [PUBLIC_DEPS ...] [DEPS ...])  -> pz_<name>, alias pz::<name>;
#     DEPS are linked PRIVATE, PUBLIC_DEPS those its headers expose.
# pz_cc_binary(NAME exe FLOOR folder SRCS ... DEPS ...)            -> executable, deps PRIVATE
# pz_cc_test(NAME name FLOOR tests/<folder> SRCS ... [LABELS ...])  -> gtest executable registered
#     with ctest, linking the libraries of its floors line (and tests/testing's helpers)
include_guard(GLOBAL)

# floors.txt -> global properties PZ_FLOOR:<folder> (the names on its line), PZ_FLOORS (folders).
set(PZ_FLOORS_FILE ${PROJECT_SOURCE_DIR}/cmake/floors.txt)
set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${PZ_FLOORS_FILE})
file(STRINGS ${PZ_FLOORS_FILE} _pz_floor_lines)
foreach(_line IN LISTS _pz_floor_lines)
  if(_line MATCHES "^[ \t]*(#|$)")
    continue()
  endif()
  if(NOT _line MATCHES "^([A-Za-z0-9_/]+):(.*)$")
    message(FATAL_ERROR "cmake/floors.txt: not 'folder: names': '${_line}'")
  endif()
  set(_folder ${CMAKE_MATCH_1})
  string(STRIP "${CMAKE_MATCH_2}" _names)
  string(REGEX REPLACE "[ \t]+" ";" _names "${_names}")
  set_property(GLOBAL PROPERTY PZ_FLOOR:${_folder} "${_names}")
  set_property(GLOBAL APPEND PROPERTY PZ_FLOORS ${_folder})
endforeach()

# The floors name of a link dependency: pz::x -> x, cppzmq -> zmq, protobuf -> protobuf; other
# outside libraries (Eigen, spdlog, …) have no rule and give "".
function(_pz_floor_name dep out)
  if(dep MATCHES "^pz::(.+)$")
    set(${out} ${CMAKE_MATCH_1} PARENT_SCOPE)
  elseif(dep STREQUAL "cppzmq")
    set(${out} zmq PARENT_SCOPE)
  elseif(dep MATCHES "^protobuf::")
    set(${out} protobuf PARENT_SCOPE)
  else()
    set(${out} "" PARENT_SCOPE)
  endif()
endfunction()

# Stops the configuration when `folder` would link something its floors line does not name.
function(pz_check_floor folder)
  get_property(_known GLOBAL PROPERTY PZ_FLOORS)
  if(NOT folder IN_LIST _known)
    message(FATAL_ERROR "${folder}/ has no line in cmake/floors.txt")
  endif()
  get_property(_allowed GLOBAL PROPERTY PZ_FLOOR:${folder})
  foreach(dep IN LISTS ARGN)
    _pz_floor_name(${dep} _name)
    if(_name AND NOT _name STREQUAL folder AND NOT _name IN_LIST _allowed)
      message(FATAL_ERROR "${folder}/ links ${dep}, which is not on its line of cmake/floors.txt "
                          "(${folder}: ${_allowed})")
    endif()
  endforeach()
endfunction()

# <build>/include/<root>/<path> -> the source folder <path>; prints the include root.
function(_pz_include_root root path out)
  set(_dir ${PROJECT_BINARY_DIR}/include/${root})
  get_filename_component(_parent ${_dir}/${path} DIRECTORY)
  file(MAKE_DIRECTORY ${_parent})
  file(CREATE_LINK ${PROJECT_SOURCE_DIR}/${path} ${_dir}/${path} SYMBOLIC)
  set(${out} ${_dir} PARENT_SCOPE)
endfunction()

function(pz_cc_library)
  cmake_parse_arguments(PZ "" "NAME" "SRCS;PUBLIC_DEPS;DEPS" ${ARGN})
  set(_t pz_${PZ_NAME})
  pz_check_floor(${PZ_NAME} ${PZ_PUBLIC_DEPS} ${PZ_DEPS})
  _pz_include_root(${PZ_NAME} ${PZ_NAME} _root)
  add_library(${_t} STATIC ${PZ_SRCS})
  target_include_directories(${_t} PUBLIC ${_root})
  target_link_libraries(${_t} PUBLIC ${PZ_PUBLIC_DEPS} PRIVATE ${PZ_DEPS})
  add_library(pz::${PZ_NAME} ALIAS ${_t})
endfunction()

function(pz_cc_binary)
  cmake_parse_arguments(PZ "" "NAME;FLOOR" "SRCS;DEPS" ${ARGN})
  pz_check_floor(${PZ_FLOOR} ${PZ_DEPS})
  add_executable(${PZ_NAME} ${PZ_SRCS})
  target_link_libraries(${PZ_NAME} PRIVATE ${PZ_DEPS})
endfunction()

# The helpers every test may include ("tests/testing/..."): an include root, nothing linked — a
# helper's own includes resolve only in the tests that link what it includes.
function(_pz_testing_target)
  if(NOT TARGET pz_testing)
    _pz_include_root(testing tests/testing _root)
    add_library(pz_testing INTERFACE)
    target_include_directories(pz_testing INTERFACE ${_root})
  endif()
endfunction()

function(pz_cc_test)
  cmake_parse_arguments(PZ "" "NAME;FLOOR;TIMEOUT" "SRCS;LABELS" ${ARGN})
  set(_t ${PZ_NAME})
  get_property(_names GLOBAL PROPERTY PZ_FLOOR:${PZ_FLOOR})
  set(_deps)
  foreach(_name IN LISTS _names)
    if(_name STREQUAL "zmq")
      list(APPEND _deps cppzmq)
    elseif(_name STREQUAL "protobuf")
      list(APPEND _deps protobuf::libprotobuf)
    else()
      list(APPEND _deps pz::${_name})
    endif()
  endforeach()
  pz_check_floor(${PZ_FLOOR} ${_deps})
  _pz_testing_target()
  string(REPLACE "/" "_" _own ${PZ_FLOOR})
  _pz_include_root(${_own} ${PZ_FLOOR} _root)
  add_executable(${_t} ${PZ_SRCS})
  target_include_directories(${_t} PRIVATE ${_root})
  target_link_libraries(${_t} PRIVATE ${_deps} pz_testing GTest::gtest GTest::gtest_main)
  target_compile_definitions(${_t} PRIVATE
    PIEZOID_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data"
    PIEZOID_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
  add_test(NAME ${_t} COMMAND ${_t})
  if(NOT PZ_TIMEOUT)
    set(PZ_TIMEOUT 300)
  endif()
  set_tests_properties(${_t} PROPERTIES TIMEOUT ${PZ_TIMEOUT} LABELS "${PZ_LABELS}")
endfunction()

# pz_embed_assets(OUT file.cc NAMESPACE ns COMMENT text ASSETS kName=path ...): generates OUT at
# build time with cmake/embed_assets.cmake, one std::string_view a name holding its file's bytes,
# again whenever a file changes (the step kernels' text, the fin plant, the dashboard's page).
function(pz_embed_assets)
  cmake_parse_arguments(E "" "OUT;NAMESPACE;COMMENT" "ASSETS" ${ARGN})
  set(paths)
  foreach(asset ${E_ASSETS})
    string(REGEX REPLACE "^[^=]*=" "" path "${asset}")
    list(APPEND paths "${path}")
  endforeach()
  add_custom_command(
    OUTPUT ${E_OUT}
    COMMAND ${CMAKE_COMMAND} -DOUT=${E_OUT} -DNAMESPACE=${E_NAMESPACE} "-DASSETS=${E_ASSETS}"
            -P ${PROJECT_SOURCE_DIR}/cmake/embed_assets.cmake
    DEPENDS ${paths} ${PROJECT_SOURCE_DIR}/cmake/embed_assets.cmake
    COMMENT "${E_COMMENT}"
    VERBATIM)
endfunction()
