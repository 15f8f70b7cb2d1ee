# Writes OUT (a header defining GAPFLOW_CODE_VERSION) at every build: the commit of SRC
# (`git rev-parse --short HEAD`), with "-dirty" when a file outside results/ differs from
# it (results/ holds what the code produced, e.g. a study's store being written while
# the code is rebuilt: not a change of the code). Rewritten only when the version
# changed, so a clean rebuild does not recompile store.cpp. Without git: FALLBACK.
set(version "${FALLBACK}")
find_package(Git QUIET)
if(GIT_FOUND)
  execute_process(COMMAND ${GIT_EXECUTABLE} rev-parse --short HEAD WORKING_DIRECTORY ${SRC}
                  OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE result ERROR_QUIET)
  execute_process(COMMAND ${GIT_EXECUTABLE} status --porcelain --untracked-files=no -- . ":(exclude)results"
                  WORKING_DIRECTORY ${SRC} OUTPUT_VARIABLE changes OUTPUT_STRIP_TRAILING_WHITESPACE
                  RESULT_VARIABLE status_result ERROR_QUIET)
  if(result EQUAL 0 AND commit)
    set(version "${commit}")
    if(NOT status_result EQUAL 0 OR changes)
      set(version "${commit}-dirty")
    endif()
  endif()
endif()
set(text "#define GAPFLOW_CODE_VERSION \"${version}\"\n")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old)
endif()
if(NOT "${old}" STREQUAL "${text}")
  file(WRITE "${OUT}" "${text}")
endif()
