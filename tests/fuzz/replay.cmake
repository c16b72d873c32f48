# Run a fuzz target once over every file in DIRS ('|'-separated folders): the past findings
# and the generated seeds. Used by the fuzz.regressions.* tests.
string(REPLACE "|" ";" dirs "${DIRS}")
set(files "")
foreach(d IN LISTS dirs)
  if(IS_DIRECTORY "${d}")
    file(GLOB found LIST_DIRECTORIES false "${d}/*")
    list(FILTER found EXCLUDE REGEX "/(README|\\.)[^/]*$")
    list(APPEND files ${found})
  endif()
endforeach()
list(SORT files)
list(LENGTH files n)
if(n EQUAL 0)
  message(FATAL_ERROR "no inputs to replay in ${DIRS} (did fuzz.seeds run?)")
endif()
# -malloc_limit_mb / -timeout: what libFuzzer checks while fuzzing, also when replaying
# (replay_main ignores flags).
execute_process(COMMAND "${EXE}" -malloc_limit_mb=1024 -rss_limit_mb=4096 -timeout=120 ${files}
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${EXE} failed (${rc}) on one of ${n} inputs")
endif()
message(STATUS "${n} inputs replayed")
