# Debian packages through CPack, one per install component:
#   libaffine-orb-dev   (component dev): the headers, the CMake package and the pkg-config file;
#                       header-only, so Architecture: all;
#   python3-affine-orb  (component python, when the module is built): the compiled module in
#                       /usr/lib/python3/dist-packages, where Debian's /usr/bin/python3 finds it.
# Configure with -DCMAKE_INSTALL_PREFIX=/usr (the module's directory depends on it), build, then
# `cpack` in the build directory writes <name>_<version>_<arch>.deb there (tests/package_check.sh).
set(CPACK_GENERATOR DEB)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_PACKAGING_INSTALL_PREFIX "${CMAKE_INSTALL_PREFIX}")
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_VENDOR "the affine_orb authors")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "the affine_orb authors")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# The first line of both packages' Description (CPack gives every component the same one); each
# package's own text follows it.
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "Affine-ORB feature extraction, matching and H/F model selection")

set(CPACK_COMPONENTS_ALL dev)
set(CPACK_DEBIAN_DEV_PACKAGE_NAME libaffine-orb-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_ARCHITECTURE all)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "libopencv-dev, libeigen3-dev")
set(CPACK_DEBIAN_DEV_DESCRIPTION
    "affine_orb, a C++17 header-only library, extracts ORB-style keypoints (FAST,
rBRIEF or BRISK descriptors) from an image and from simulated tilted views of it,
matches binary descriptors and selects a homography or a fundamental matrix.
This package has its headers, its CMake package (find_package(affine_orb)) and
its pkg-config file (affine_orb).")

if(TARGET affine_orb_python)
  list(APPEND CPACK_COMPONENTS_ALL python)
  set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-affine-orb)
  set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
  # The module is built for one Python minor version (its file name says cpython-3XY), the one of
  # AFFINE_ORB_PYTHON_VERSION (set by adapters/python); the OpenCV libraries it links come from
  # dpkg-shlibdeps.
  set(CPACK_DEBIAN_PYTHON_PACKAGE_SHLIBDEPS ON)
  string(REGEX MATCH "^([0-9]+)\\.([0-9]+)$" _ "${AFFINE_ORB_PYTHON_VERSION}")
  math(EXPR affine_orb_python_next_minor "${CMAKE_MATCH_2} + 1")
  set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS "python3 (>= ${AFFINE_ORB_PYTHON_VERSION}), \
python3 (<< ${CMAKE_MATCH_1}.${affine_orb_python_next_minor}), python3-numpy, python3-opencv")
  set(CPACK_DEBIAN_PYTHON_DESCRIPTION
      "The Python 3 module affine_orb: Extractor, match and select_model over the C++ library
affine_orb, with numpy arrays and cv2 keypoints at the boundary.")
endif()

# The licence, as Debian's copyright file of each package. EXCLUDE_FROM_ALL: installed into the
# packages (which install one component at a time) and not by a plain `cmake --install`.
foreach(component ${CPACK_COMPONENTS_ALL})
  string(TOUPPER ${component} upper)
  install(FILES ${PROJECT_SOURCE_DIR}/LICENSE RENAME copyright
          DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/${CPACK_DEBIAN_${upper}_PACKAGE_NAME}
          COMPONENT ${component} EXCLUDE_FROM_ALL)
endforeach()

include(CPack)
