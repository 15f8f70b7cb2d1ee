# Writes OUT (a header defining GAPFLOW_CODE_VERSION) from `git describe --always --dirty`
# in SRC, at every build, rewriting it only when the version changed (so a clean rebuild
# does not recompile store.cpp). Without git: FALLBACK.
set(version "${FALLBACK}")
find_package(Git QUIET)
if(GIT_FOUND)
  execute_process(COMMAND ${GIT_EXECUTABLE} describe --always --dirty WORKING_DIRECTORY ${SRC}
                  OUTPUT_VARIABLE described OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE result ERROR_QUIET)
  if(result EQUAL 0 AND described)
    set(version "${described}")
  endif()
endif()
set(text "#define GAPFLOW_CODE_VERSION \"${version}\"\n")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old)
endif()
if(NOT "${old}" STREQUAL "${text}")
  file(WRITE "${OUT}" "${text}")
endif()
