# Runs every example with a bad value for each of its numeric options and requires exit code 2 and
# a message on stderr that names the option and the value. Run by ctest as examples_cli_errors:
#   cmake -DBIN=<dir of the example programs> -DIMAGE=<a readable image> -DSEQUENCE=<a directory> -P ...
set(cases
    "affine_orb_match,--features,--max-tilt,--threads"
    "affine_orb_extract,--features,--view-features,--max-tilt,--threads,--repeat"
    "affine_orb_sequence,--step,--max-tilt,--features,--threads,--frames,--min-inliers,--keyframe-ratio,--max-lost")
set(failures "")
foreach(case ${cases})
  string(REPLACE "," ";" parts "${case}")
  list(GET parts 0 program)
  list(SUBLIST parts 1 -1 flags)
  if(program STREQUAL "affine_orb_match")
    set(positional "")
  elseif(program STREQUAL "affine_orb_extract")
    set(positional "${IMAGE}")
  else()
    set(positional "${SEQUENCE}")
  endif()
  foreach(flag ${flags})
    foreach(value abc 9000x 1.5.2)
      execute_process(COMMAND "${BIN}/${program}" ${positional} ${flag} ${value} RESULT_VARIABLE rc
                      OUTPUT_QUIET ERROR_VARIABLE err)
      string(FIND "${err}" "${flag}: expected" named)
      string(FIND "${err}" "\"${value}\"" quoted)
      if(NOT rc EQUAL 2 OR named EQUAL -1 OR quoted EQUAL -1)
        string(APPEND failures "${program} ${flag} ${value}: exit ${rc}, stderr: ${err}\n")
      endif()
    endforeach()
  endforeach()
endforeach()
if(failures)
  message(FATAL_ERROR "bad numeric values not reported as expected:\n${failures}")
endif()
