# The forks' own ORB extractors (AFFINE_ORB_STOCK_EXTRACTORS_DIR, by default
# ../shared/slam/stock_extractors: ORB-SLAM2 f2e6f51 and ORB-SLAM3 060181f, GPLv3) compiled from
# where they lie into the static library affine_orb_stock (tests/stock/stock_extractor.hpp), and
# stella_vslam b0e60d6's (BSD-2) into affine_orb_stock_stella (tests/stock/stock_stella.hpp), for
# the conformance tests and benchmarks that compare affine_orb with them; nothing of them enters
# this tree or its install. Where the folder is absent there is no such target, and the programs
# that need it are built without it and say so.
set(AFFINE_ORB_STOCK_EXTRACTORS_DIR "${PROJECT_SOURCE_DIR}/../shared/slam/stock_extractors" CACHE PATH
    "The forks' own ORB extractors (orbslam2_f2e6f51/, orbslam3_060181f/, stella_vslam_b0e60d6/), for conformance tests and benches")
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

# stella_vslam's extractor needs yaml-cpp, nlohmann-json and spdlog (Debian: libyaml-cpp-dev,
# nlohmann-json3-dev, libspdlog-dev; tests/install_deps.sh) besides OpenCV and Eigen.
set(affine_orb_stock_stella ${AFFINE_ORB_STOCK_EXTRACTORS_DIR}/stella_vslam_b0e60d6)
if(EXISTS ${affine_orb_stock_stella}/stella_vslam/feature/orb_extractor.cc)
  find_package(yaml-cpp QUIET)
  find_package(nlohmann_json 3 QUIET)
  find_package(spdlog QUIET)
  find_package(Eigen3 3.3 QUIET NO_MODULE)
  if(yaml-cpp_FOUND AND nlohmann_json_FOUND AND spdlog_FOUND AND Eigen3_FOUND)
    find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc features2d)
    set(feature ${affine_orb_stock_stella}/stella_vslam/feature)
    add_library(affine_orb_stock_stella STATIC ${PROJECT_SOURCE_DIR}/tests/stock/stock_stella.cpp
                ${feature}/orb_extractor.cc ${feature}/orb_impl.cc ${feature}/orb_params.cc)
    target_include_directories(affine_orb_stock_stella PUBLIC ${PROJECT_SOURCE_DIR}/tests/stock
                               PRIVATE ${affine_orb_stock_stella})
    # Its own build's defaults: no OpenMP, no SSE3 descriptor path (USE_SSE_ORB off).
    target_link_libraries(affine_orb_stock_stella PUBLIC opencv_core opencv_imgproc opencv_features2d
                          PRIVATE yaml-cpp nlohmann_json::nlohmann_json spdlog::spdlog Eigen3::Eigen)
    target_compile_options(affine_orb_stock_stella PRIVATE -w -fno-sanitize=undefined)
    set_target_properties(affine_orb_stock_stella PROPERTIES POSITION_INDEPENDENT_CODE ON)
    # The same in a renamed namespace, for the stella_vslam adapter's test, which links the adapter's
    # stella_vslam::feature::orb_extractor beside it.
    add_library(affine_orb_stock_stella_renamed STATIC ${PROJECT_SOURCE_DIR}/tests/stock/stock_stella.cpp
                ${feature}/orb_extractor.cc ${feature}/orb_impl.cc ${feature}/orb_params.cc)
    target_include_directories(affine_orb_stock_stella_renamed PUBLIC ${PROJECT_SOURCE_DIR}/tests/stock
                               PRIVATE ${affine_orb_stock_stella})
    target_compile_definitions(affine_orb_stock_stella_renamed PRIVATE stella_vslam=affine_orb_stock_stella)
    target_link_libraries(affine_orb_stock_stella_renamed PUBLIC opencv_core opencv_imgproc opencv_features2d
                          PRIVATE yaml-cpp nlohmann_json::nlohmann_json spdlog::spdlog Eigen3::Eigen)
    target_compile_options(affine_orb_stock_stella_renamed PRIVATE -w -fno-sanitize=undefined)
  else()
    message(STATUS "affine_orb: stella_vslam's extractor needs the yaml-cpp, nlohmann-json, spdlog and Eigen "
                   "headers (libyaml-cpp-dev nlohmann-json3-dev libspdlog-dev libeigen3-dev): the conformance "
                   "test against it and its bench_fork_extraction rows are not built")
  endif()
else()
  message(STATUS "affine_orb: no stella_vslam extractor in ${affine_orb_stock_stella}: the conformance test "
                 "against it and its bench_fork_extraction rows are not built")
endif()
