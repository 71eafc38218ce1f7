# The forks' own ORB extractors (AFFINE_ORB_STOCK_EXTRACTORS_DIR, by default
# ../shared/slam/stock_extractors: ORB-SLAM2 f2e6f51 and ORB-SLAM3 060181f, GPLv3) compiled from
# where they lie into the static library affine_orb_stock (tests/stock/stock_extractor.hpp), for
# the conformance tests and benchmarks that compare affine_orb with them; nothing of them enters
# this tree or its install. Where the folder is absent there is no such target, and the programs
# that need it are built without it and say so.
set(AFFINE_ORB_STOCK_EXTRACTORS_DIR "${PROJECT_SOURCE_DIR}/../shared/slam/stock_extractors" CACHE PATH
    "The forks' own ORB extractors (orbslam2_f2e6f51/, orbslam3_060181f/), for conformance tests and benches")
set(affine_orb_stock_orbslam2 ${AFFINE_ORB_STOCK_EXTRACTORS_DIR}/orbslam2_f2e6f51)
set(affine_orb_stock_orbslam3 ${AFFINE_ORB_STOCK_EXTRACTORS_DIR}/orbslam3_060181f)
if(EXISTS ${affine_orb_stock_orbslam2}/ORBextractor.cc AND EXISTS ${affine_orb_stock_orbslam3}/ORBextractor.cc)
  find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc features2d)
  # ORB-SLAM2's header includes <opencv/cv.h>, which OpenCV 4 no longer has: its two files are
  # copied to the build tree with <opencv2/opencv.hpp> in its place, the one edit its README names.
  set(copy ${PROJECT_BINARY_DIR}/stock_extractors/orbslam2)
  configure_file(${affine_orb_stock_orbslam2}/ORBextractor.cc ${copy}/ORBextractor.cc COPYONLY)
  file(READ ${affine_orb_stock_orbslam2}/ORBextractor.h header)
  string(REPLACE "#include <opencv/cv.h>" "#include <opencv2/opencv.hpp>" header "${header}")
  file(CONFIGURE OUTPUT ${copy}/ORBextractor.h CONTENT "${header}")
  foreach(fork 2 3)
    if(fork EQUAL 2)
      set(dir ${copy})
    else()
      set(dir ${affine_orb_stock_orbslam3})
    endif()
    add_library(affine_orb_stock_orbslam${fork} OBJECT ${dir}/ORBextractor.cc ${PROJECT_SOURCE_DIR}/tests/stock/stock_fork.cpp)
    target_include_directories(affine_orb_stock_orbslam${fork} PRIVATE ${dir} ${PROJECT_SOURCE_DIR}/tests/stock)
    # The fork's namespace renamed, so that a program may link an adapter (ORB_SLAM2::ORBextractor
    # too) beside it.
    target_compile_definitions(affine_orb_stock_orbslam${fork} PRIVATE AFFINE_ORB_STOCK_ORBSLAM=${fork}
                               ORB_SLAM${fork}=affine_orb_stock_orbslam${fork})
    target_link_libraries(affine_orb_stock_orbslam${fork} PRIVATE opencv_core opencv_imgproc opencv_features2d)
    # The forks' code is the reference, not under test: no warnings, and the undefined-behaviour
    # sanitizer of a sanitizer build does not judge it.
    target_compile_options(affine_orb_stock_orbslam${fork} PRIVATE -w -fno-sanitize=undefined)
    set_target_properties(affine_orb_stock_orbslam${fork} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  endforeach()
  add_library(affine_orb_stock STATIC ${PROJECT_SOURCE_DIR}/tests/stock/stock_extractor.cpp
                                      $<TARGET_OBJECTS:affine_orb_stock_orbslam2> $<TARGET_OBJECTS:affine_orb_stock_orbslam3>)
  target_include_directories(affine_orb_stock PUBLIC ${PROJECT_SOURCE_DIR}/tests/stock)
  target_link_libraries(affine_orb_stock PUBLIC opencv_core opencv_imgproc opencv_features2d)
else()
  message(STATUS "affine_orb: no stock extractors in ${AFFINE_ORB_STOCK_EXTRACTORS_DIR}: the conformance "
                 "tests against the forks' own extractors and bench_fork_extraction are not built")
endif()
