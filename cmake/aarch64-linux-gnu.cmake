# Cross-compiles for aarch64 Linux with Debian's g++-aarch64-linux-gnu; the programs run under
# qemu-user (CMAKE_CROSSCOMPILING_EMULATOR, so ctest runs them as it runs native ones).
# AFFINE_ORB_AARCH64_SYSROOT is a directory into which Debian's arm64 packages of OpenCV (core,
# imgproc, imgcodecs, features2d and what they depend on), Eigen and doctest were unpacked
# (tests/cross_aarch64.sh makes it): libraries and headers are searched there only, and
# cmake/aarch64/OpenCVConfig.cmake declares the OpenCV modules from it.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

if(NOT AFFINE_ORB_AARCH64_SYSROOT)
  message(FATAL_ERROR "cmake/aarch64-linux-gnu.cmake: set AFFINE_ORB_AARCH64_SYSROOT to the unpacked arm64 packages")
endif()
# try_compile() projects are configured with this file too and need the variable.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES AFFINE_ORB_AARCH64_SYSROOT)

set(CMAKE_FIND_ROOT_PATH "${AFFINE_ORB_AARCH64_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(OpenCV_DIR "${CMAKE_CURRENT_LIST_DIR}/aarch64" CACHE PATH "OpenCV for aarch64 (the sysroot's libraries)")

# The linker follows the OpenCV libraries' own dependencies inside the sysroot: the multiarch
# directories, /usr/lib (HDF4, OGDI of GDAL) and the RUNPATH of Samba's libraries (through libsmbclient).
set(affine_orb_aarch64_libs)
foreach(dir usr/lib/aarch64-linux-gnu lib/aarch64-linux-gnu usr/lib usr/lib/aarch64-linux-gnu/samba)
  list(APPEND affine_orb_aarch64_libs "${AFFINE_ORB_AARCH64_SYSROOT}/${dir}")
endforeach()
list(JOIN affine_orb_aarch64_libs ":" affine_orb_aarch64_path)
set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,-rpath-link,${affine_orb_aarch64_path}")

# -ffp-contract=off: GCC fuses a·b + c into one rounding on AArch64 by default, so the
# floating-point code (angles, mapped positions, BRISK's sampling) would round differently from
# x86's; without fusion the features are x86's bytes except rBRIEF's angles, which come from
# cv::fastAtan2 and so from the arm64 OpenCV build's own rounding (docs/speed.md).
set(CMAKE_CXX_FLAGS_INIT "-ffp-contract=off")

find_program(AFFINE_ORB_QEMU_AARCH64 NAMES qemu-aarch64 qemu-aarch64-static REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR "${AFFINE_ORB_QEMU_AARCH64};-L;${AFFINE_ORB_AARCH64_SYSROOT}")
