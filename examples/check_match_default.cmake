# affine_orb_match with no arguments, in a scratch directory: exit 0, matches.png and rectified.png
# written, and a line saying which homography rectified image 2. Run by ctest as
# example_match_default.
set(dir "${CMAKE_CURRENT_BINARY_DIR}/match_default")
file(REMOVE_RECURSE "${dir}")
file(MAKE_DIRECTORY "${dir}")
execute_process(COMMAND "${PROGRAM}" WORKING_DIRECTORY "${dir}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "affine_orb_match failed (${rc}): ${err}")
endif()
foreach(file matches.png rectified.png)
  if(NOT EXISTS "${dir}/${file}")
    message(FATAL_ERROR "affine_orb_match wrote no ${file}:\n${out}")
  endif()
endforeach()
if(NOT out MATCHES "image 2 rectified (into image 1's frame|with the estimated homography although F was chosen)")
  message(FATAL_ERROR "affine_orb_match did not say how it rectified:\n${out}")
endif()
message(STATUS "${out}")
