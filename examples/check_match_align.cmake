# affine_orb_match --align on opencv-doc's graf 1 -> 3 against its ground truth H1to3p.xml: the
# aligned image-2 points lie at under half the median distance from where the ground truth puts
# them that the keypoints' positions do, the JSON counts the aligned matches (null without
# --align), and --align with --one-shot is refused. Run by ctest as example_match_align.
set(images "${DIR}/graf1.png" "${DIR}/graf3.png" --homography "${DIR}/H1to3p.xml" --json)

# ${name}: the JSON line of affine_orb_match on the pair with the options after `name`.
function(run name)
  execute_process(COMMAND "${PROGRAM}" ${images} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "affine_orb_match ${ARGN} failed (${rc}): ${err}")
  endif()
  set(${name} "${out}" PARENT_SCOPE)
endfunction()

# ${name}: the value of `key` in the JSON line `json` (string(JSON) gives ON for true, "" for null).
function(json_value name json key)
  string(JSON value GET "${json}" "${key}")
  set(${name} "${value}" PARENT_SCOPE)
endfunction()

run(plain)
run(aligned --align)
json_value(plain_error "${plain}" median_correct_error)
json_value(aligned_error "${aligned}" median_correct_error)
json_value(plain_count "${plain}" aligned)
json_value(aligned_count "${aligned}" aligned)
json_value(verified "${aligned}" verified)
json_value(correct "${aligned}" correct)
if(NOT verified STREQUAL "ON")
  message(FATAL_ERROR "graf 1 -> 3 should be verified with --align:\n${aligned}")
endif()
if(NOT plain_count STREQUAL "")
  message(FATAL_ERROR "without --align the JSON should say \"aligned\": null:\n${plain}")
endif()
if(NOT aligned_count GREATER 200)
  message(FATAL_ERROR "--align should align more than 200 of the ${correct} correct matches:\n${aligned}")
endif()
# The errors in ten-thousandths of a pixel (string(JSON) gives every digit of the double; math()
# reads a leading zero as decimal).
string(REGEX REPLACE "^([0-9]+)\\.([0-9][0-9][0-9][0-9]).*$" "\\1\\2" plain_e4 "${plain_error}")
string(REGEX REPLACE "^([0-9]+)\\.([0-9][0-9][0-9][0-9]).*$" "\\1\\2" aligned_e4 "${aligned_error}")
math(EXPR twice_aligned "2 * ${aligned_e4}")
if(NOT twice_aligned LESS plain_e4)
  message(FATAL_ERROR "aligned points ${aligned_e4} from the ground truth (median, 1e-4 px), the keypoints "
                      "${plain_e4}: alignment should halve it at least")
endif()
message(STATUS "median distance from the ground truth of the correct matches, 1e-4 px: keypoints ${plain_e4}, "
               "aligned ${aligned_e4} (${aligned_count} aligned)")

execute_process(COMMAND "${PROGRAM}" --one-shot --align RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "--align: ")
  message(FATAL_ERROR "--one-shot --align: exit ${rc} (2 expected), stderr: ${err}")
endif()
