# affine_orb_match on EVD adam, which no stage verifies: the JSON output says the last stage's
# search gave the chosen homography by default and not with --no-last-stage-search, the text output
# says so instead of the parallax verdict (which belongs to the estimate the search replaced), both
# name the test that refused the pair (the precision test for the search's homography, the inlier
# count without the search), and --one-shot refuses the flag with exit code 2. Run by ctest as example_match_search:
#   cmake -DPROGRAM=<affine_orb_match> -DDATA=<../shared/data> -P ...
# Without DATA/pairs/evd/adam it prints "skipped: ..." (the test's SKIP_REGULAR_EXPRESSION).
set(image1 "${DATA}/pairs/evd/adam/1.png")
set(image2 "${DATA}/pairs/evd/adam/2.png")
if(NOT EXISTS "${image1}" OR NOT EXISTS "${image2}")
  message("skipped: no ${DATA}/pairs/evd/adam (../shared/data)")
  return()
endif()
function(run out_var)
  execute_process(COMMAND "${PROGRAM}" "${image1}" "${image2}" --threads 1 ${ARGN} RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc)
    message(FATAL_ERROR "affine_orb_match ${ARGN}: exit ${rc}: ${err}")
  endif()
  set(${out_var} "${out}" PARENT_SCOPE)
endfunction()
run(searched --json)
run(plain --json --no-last-stage-search)
if(NOT plain MATCHES "\"verified\": false, \"last_stage_search\": false, \"failure\": \"few inliers\",")
  message(FATAL_ERROR "with --no-last-stage-search EVD adam should end unverified, unsearched:\n${plain}")
endif()
if(NOT searched MATCHES "\"verified\": false, \"last_stage_search\": true, \"failure\": \"imprecise\"," OR
   NOT searched MATCHES "\"model\": \"homography\"")
  message(FATAL_ERROR "by default the search should give EVD adam's homography:\n${searched}")
endif()
run(text)
if(NOT text MATCHES "\nmodel homography \\(the last stage's search for a homography alone\\), [0-9]+ inliers\n")
  message(FATAL_ERROR "the model line should name the search:\n${text}")
endif()
if(NOT text MATCHES "\nnot verified after stage 2 of 2 [^:]*: the homographies of its inliers' two halves map image 1's corners [0-9.]+ px apart \\(at most 10\\)\n")
  message(FATAL_ERROR "the text should name the precision test as what refused the pair:\n${text}")
endif()
execute_process(COMMAND "${PROGRAM}" --one-shot --no-last-stage-search RESULT_VARIABLE rc OUTPUT_QUIET
                ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "--no-last-stage-search: ")
  message(FATAL_ERROR "--one-shot --no-last-stage-search: exit ${rc} (2 expected), stderr: ${err}")
endif()
message(STATUS "${text}")
