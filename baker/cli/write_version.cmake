# Writes version.cpp with the version string: the project version, "+g<revision>" when the source is a git
# checkout, and "+dirty" when tracked files differ from that revision. Run at every build (cli/CMakeLists.txt),
# not only when CMake configures, so a report, an EXR's hfbake:version and --version name the revision the
# binary was built from; configure_file leaves version.cpp untouched (nothing recompiles) when the string
# is the same. In: SRC (the source tree), IN (version.cpp.in), OUT, VERSION.
execute_process(COMMAND git -C ${SRC} rev-parse --short HEAD OUTPUT_VARIABLE rev OUTPUT_STRIP_TRAILING_WHITESPACE
                RESULT_VARIABLE rev_failed ERROR_QUIET)
set(HFBAKE_VERSION_STRING ${VERSION})
if(NOT rev_failed AND rev)
  string(APPEND HFBAKE_VERSION_STRING "+g${rev}")
  execute_process(COMMAND git -C ${SRC} status --porcelain --untracked-files=no OUTPUT_VARIABLE changes
                  RESULT_VARIABLE status_failed ERROR_QUIET)
  if(NOT status_failed AND NOT changes STREQUAL "")
    string(APPEND HFBAKE_VERSION_STRING "+dirty")
  endif()
endif()
configure_file(${IN} ${OUT} @ONLY)
