# The floors in the build itself: a file planted in a folder, compiled with the exact command the
# build uses for that folder's sources (compile_commands.json), must fail on an upward include and
# pass on a downward one. Run by ctest as layout_planted_build:
#   cmake -DBUILD=<build dir> -P tests/layout/planted_build.cmake
# Only the preprocessor runs: whether the include resolves is the question.
cmake_minimum_required(VERSION 3.22)
if(NOT BUILD)
  message(FATAL_ERROR "usage: cmake -DBUILD=<build dir> -P planted_build.cmake")
endif()
file(READ ${BUILD}/compile_commands.json commands)
string(JSON count LENGTH "${commands}")
math(EXPR last "${count} - 1")

# "<source of the folder>|<include>|fails or builds"
set(cases
  "model/signal.cc|opt/ga.h|fails"
  "model/signal.cc|service/wire_codec.h|fails"
  "opt/ga.cc|service/wire_codec.h|fails"
  "opt/ga.cc|wire.pb.h|fails"
  "hgann/hgann_job.cc|kinds/kinds.h|fails"
  "worker/worker.cc|master/broker.h|fails"
  "client/cmd_service.cc|master/job_store.h|fails"
  "client/cmd_service.cc|worker/worker.h|fails"
  "svcclient/job_file.cc|client/commands.h|fails"
  "svcclient/job_file.cc|kinds/kinds.h|fails"
  "tests/model/beam_test.cc|opt/ga.h|fails"
  "opt/ga.cc|model/signal.h|builds"
  "worker/worker.cc|service/wire_codec.h|builds"
  "client/cmd_service.cc|kinds/kinds.h|builds"
  "client/cmd_service.cc|svcclient/job_file.h|builds")

# In a folder of its own: a quoted include searches the including file's folder first, and the
# build folder may hold anything (generated files of an older layout, say).
set(planted_dir ${BUILD}/layout_planted)
file(REMOVE_RECURSE ${planted_dir})
file(MAKE_DIRECTORY ${planted_dir})
set(planted ${planted_dir}/planted_include.cc)
set(failures 0)
foreach(case IN LISTS cases)
  string(REPLACE "|" ";" case "${case}")
  list(GET case 0 source)
  list(GET case 1 include)
  list(GET case 2 expected)
  set(command "")
  foreach(i RANGE ${last})
    string(JSON file GET "${commands}" ${i} file)
    if(file MATCHES "/${source}$")
      string(JSON command GET "${commands}" ${i} command)
      string(JSON directory GET "${commands}" ${i} directory)
      break()
    endif()
  endforeach()
  if(command STREQUAL "")
    message(SEND_ERROR "${source}: not in ${BUILD}/compile_commands.json")
    math(EXPR failures "${failures} + 1")
    continue()
  endif()
  # The build's command with the planted file instead of the source, preprocessing only.
  separate_arguments(args UNIX_COMMAND "${command}")
  set(run "")
  set(skip FALSE)
  foreach(arg IN LISTS args)
    if(skip)
      set(skip FALSE)
    elseif(arg MATCHES "^(-o|-MF|-MT)$")
      set(skip TRUE)
    elseif(NOT arg MATCHES "^(-c|-MD)$" AND NOT arg STREQUAL file AND NOT arg MATCHES "ccache$")
      list(APPEND run "${arg}")
    endif()
  endforeach()
  file(WRITE ${planted} "#include \"${include}\"\n")
  execute_process(COMMAND ${run} -E -o /dev/null ${planted} WORKING_DIRECTORY ${directory}
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(rc EQUAL 0)
    set(got builds)
  else()
    set(got fails)
  endif()
  message(STATUS "${source} + #include \"${include}\": ${got}")
  if(NOT got STREQUAL expected)
    message(SEND_ERROR "${source} + #include \"${include}\": ${got}, should ${expected}\n${err}")
    math(EXPR failures "${failures} + 1")
  endif()
endforeach()
file(REMOVE_RECURSE ${planted_dir})
if(failures GREATER 0)
  message(FATAL_ERROR "${failures} planted includes did not do what the floors say")
endif()
