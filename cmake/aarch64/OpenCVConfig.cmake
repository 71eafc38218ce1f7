# The OpenCV modules the aarch64 tests link (cmake/aarch64-linux-gnu.cmake), as imported targets
# of the arm64 libraries unpacked into AFFINE_ORB_AARCH64_SYSROOT. Debian's own OpenCVConfig.cmake
# comes with libopencv-dev:arm64, which depends on every module's package; this declares only the
# modules that are unpacked.
set(OpenCV_VERSION 4.6.0)
set(OpenCV_VERSION_MAJOR 4)
set(affine_orb_opencv_root "${AFFINE_ORB_AARCH64_SYSROOT}/usr")
set(OpenCV_INCLUDE_DIRS "${affine_orb_opencv_root}/include/opencv4"
                        "${affine_orb_opencv_root}/include/aarch64-linux-gnu/opencv4")
set(affine_orb_opencv_modules core imgproc imgcodecs features2d flann calib3d)
set(OpenCV_LIBS)
foreach(module ${affine_orb_opencv_modules})
  set(library "${affine_orb_opencv_root}/lib/aarch64-linux-gnu/libopencv_${module}.so.406")
  if(NOT TARGET opencv_${module} AND EXISTS "${library}")
    add_library(opencv_${module} SHARED IMPORTED)
    set_target_properties(opencv_${module} PROPERTIES IMPORTED_LOCATION "${library}"
                                                      INTERFACE_INCLUDE_DIRECTORIES "${OpenCV_INCLUDE_DIRS}")
  endif()
  if(TARGET opencv_${module})
    list(APPEND OpenCV_LIBS opencv_${module})
  endif()
endforeach()
foreach(component ${OpenCV_FIND_COMPONENTS})
  if(NOT TARGET opencv_${component})
    set(OpenCV_FOUND FALSE)
    set(OpenCV_NOT_FOUND_MESSAGE "opencv_${component} is not in ${AFFINE_ORB_AARCH64_SYSROOT}")
  endif()
endforeach()
