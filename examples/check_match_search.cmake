# affine_orb_match --last-stage-search on Oxford bark 1->6, which no stage verifies: the JSON output
# says the search gave the chosen homography with the flag and not without it, the text output says
# so instead of the parallax verdict (which belongs to the estimate the search replaced), and
# --one-shot refuses the flag with exit code 2. Run by ctest as example_match_search:
#   cmake -DPROGRAM=<affine_orb_match> -DDATA=<../shared/data> -P ...
# Without DATA/oxford/bark it prints "skipped: ..." (the test's SKIP_REGULAR_EXPRESSION).
set(image1 "${DATA}/oxford/bark/img1.png")
set(image6 "${DATA}/oxford/bark/img6.png")
if(NOT EXISTS "${image1}" OR NOT EXISTS "${image6}")
  message("skipped: no ${DATA}/oxford/bark (../shared/data)")
  return()
endif()
function(run out_var)
  execute_process(COMMAND "${PROGRAM}" "${image1}" "${image6}" --threads 1 ${ARGN} RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc)
    message(FATAL_ERROR "affine_orb_match ${ARGN}: exit ${rc}: ${err}")
  endif()
  set(${out_var} "${out}" PARENT_SCOPE)
endfunction()
run(plain --json)
run(searched --json --last-stage-search)
if(NOT plain MATCHES "\"verified\": false, \"last_stage_search\": false,")
  message(FATAL_ERROR "without --last-stage-search bark 1->6 should end unverified, unsearched:\n${plain}")
endif()
if(NOT searched MATCHES "\"verified\": false, \"last_stage_search\": true," OR
   NOT searched MATCHES "\"model\": \"homography\"")
  message(FATAL_ERROR "--last-stage-search should give bark 1->6's homography:\n${searched}")
endif()
run(text --last-stage-search)
if(NOT text MATCHES "\nmodel homography \\(the last stage's search for a homography alone\\), [0-9]+ inliers\n")
  message(FATAL_ERROR "the model line should name the search:\n${text}")
endif()
execute_process(COMMAND "${PROGRAM}" --one-shot --last-stage-search RESULT_VARIABLE rc OUTPUT_QUIET
                ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "--last-stage-search: ")
  message(FATAL_ERROR "--one-shot --last-stage-search: exit ${rc} (2 expected), stderr: ${err}")
endif()
message(STATUS "${text}")
