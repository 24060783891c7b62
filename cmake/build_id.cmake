# Writes OUT, a header defining PIEZOID_BUILD_ID (the checkout's `git describe --always --dirty`, or
# "unknown" outside a git checkout), and rewrites it only when the id changes, so that a build
# recompiles what includes it only after a commit. Run at every build by the target pz_build_id.
execute_process(COMMAND git -C "${SRC}" describe --always --dirty --abbrev=12
                OUTPUT_VARIABLE id OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR id STREQUAL "")
  set(id "unknown")
endif()
set(content "#define PIEZOID_BUILD_ID \"${id}\"\n")
set(old "")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old)
endif()
if(NOT old STREQUAL content)
  file(WRITE "${OUT}" "${content}")
endif()
