# Builds and runs tests/consumer against an installed affine_orb, twice: with find_package(affine_orb)
# and with the flags of `pkg-config --cflags --libs affine_orb`; each must find the installed files
# under the prefix and print the expected version. With the pkg-config flags it also builds and runs
# moved_paths.cpp, which includes every header at its include path of 0.1.
#   cmake -DBINARY_DIR=<build tree> ...   installs the build tree into WORK_DIR/prefix first (ctest's
#                                         install_consumer), then also imports the Python module
#                                         from there when the build made one;
#   cmake -DPREFIX=<prefix> ...           uses what is installed there (tests/package_check.sh: /usr).
# Both with -DSOURCE_DIR=tests/consumer -DWORK_DIR=<scratch> -DGENERATOR=<cmake generator>
# -DCXX=<C++ compiler> -DVERSION=<expected version> -P check.cmake.
if(NOT WORK_DIR OR NOT (BINARY_DIR OR PREFIX))
  message(FATAL_ERROR "usage: cmake -DBINARY_DIR=<build tree> | -DPREFIX=<prefix> -DWORK_DIR=<scratch> ... -P check.cmake")
endif()
file(REMOVE_RECURSE "${WORK_DIR}")
if(BINARY_DIR)
  set(PREFIX "${WORK_DIR}/prefix")
  execute_process(COMMAND "${CMAKE_COMMAND}" --install "${BINARY_DIR}" --prefix "${PREFIX}" RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "install failed")
  endif()
endif()
set(expected_output "affine_orb ${VERSION}: [1-9][0-9]* features")

# build_and_run(<how> <program> <build command>...): builds the consumer with the command, runs
# <program> and requires the expected output (left in `out`).
function(build_and_run how program)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "building the consumer with ${how} failed")
  endif()
  execute_process(COMMAND "${program}" RESULT_VARIABLE rc OUTPUT_VARIABLE out)
  if(rc OR NOT out MATCHES "${expected_output}")
    message(FATAL_ERROR "the consumer (${how}) printed \"${out}\" (exit ${rc}), expected \"${expected_output}\"")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

# find_package(affine_orb): the package in PREFIX/share/cmake/affine_orb.
execute_process(COMMAND "${CMAKE_COMMAND}" -S "${SOURCE_DIR}" -B "${WORK_DIR}/build" -G "${GENERATOR}"
                        "-DCMAKE_PREFIX_PATH=${PREFIX}" -DCMAKE_BUILD_TYPE=Release RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "configuring the consumer with find_package(affine_orb) failed")
endif()
file(STRINGS "${WORK_DIR}/build/CMakeCache.txt" package_dir REGEX "^affine_orb_DIR:")
string(REGEX REPLACE "^[^=]*=" "" package_dir "${package_dir}")
file(REAL_PATH "${PREFIX}" real_prefix)
file(REAL_PATH "${package_dir}" package_dir)
if(NOT package_dir STREQUAL "${real_prefix}/share/cmake/affine_orb")
  message(FATAL_ERROR "find_package(affine_orb) found ${package_dir}, not ${real_prefix}/share/cmake/affine_orb")
endif()
build_and_run(find_package "${WORK_DIR}/build/consumer" "${CMAKE_COMMAND}" --build "${WORK_DIR}/build")

# pkg-config: the .pc under PREFIX/share/pkgconfig, its include directory PREFIX/include.
set(ENV{PKG_CONFIG_PATH} "${PREFIX}/share/pkgconfig")
execute_process(COMMAND pkg-config --cflags --libs affine_orb RESULT_VARIABLE rc OUTPUT_VARIABLE flags
                ERROR_VARIABLE err OUTPUT_STRIP_TRAILING_WHITESPACE)
execute_process(COMMAND pkg-config --variable=includedir affine_orb OUTPUT_VARIABLE include_dir
                OUTPUT_STRIP_TRAILING_WHITESPACE)
execute_process(COMMAND pkg-config --modversion affine_orb OUTPUT_VARIABLE pc_version OUTPUT_STRIP_TRAILING_WHITESPACE)
if(rc)
  message(FATAL_ERROR "pkg-config --cflags --libs affine_orb failed: ${err}")
endif()
file(REAL_PATH "${include_dir}" include_dir)
if(NOT include_dir STREQUAL "${real_prefix}/include" OR NOT pc_version STREQUAL VERSION)
  message(FATAL_ERROR "pkg-config gives version ${pc_version}, include directory ${include_dir}; expected ${VERSION}, "
                      "${real_prefix}/include")
endif()
separate_arguments(flags UNIX_COMMAND "${flags}")
build_and_run("pkg-config (${flags})" "${WORK_DIR}/consumer_pkg_config"
              "${CXX}" -std=c++17 -O1 "${SOURCE_DIR}/main.cpp" -o "${WORK_DIR}/consumer_pkg_config" ${flags})

# The include paths of 0.1 (every installed affine_orb/*.hpp but the umbrella and version.hpp):
# moved_paths.cpp includes each, each still compiles and warns with its new path, the program runs.
file(GLOB old_paths RELATIVE "${PREFIX}/include" "${PREFIX}/include/affine_orb/*.hpp")
list(REMOVE_ITEM old_paths affine_orb/affine_orb.hpp affine_orb/version.hpp)
file(READ "${SOURCE_DIR}/moved_paths.cpp" moved_paths_source)
# -Wsystem-headers: installed under /usr (the Debian package) they are system headers, whose
# warnings GCC hides otherwise.
execute_process(COMMAND "${CXX}" -std=c++17 -O1 -Wsystem-headers "${SOURCE_DIR}/moved_paths.cpp"
                        -o "${WORK_DIR}/moved_paths" ${flags}
                RESULT_VARIABLE rc ERROR_VARIABLE warnings)
if(rc)
  message(FATAL_ERROR "building tests/consumer/moved_paths.cpp failed:\n${warnings}")
endif()
foreach(old_path ${old_paths})
  string(FIND "${moved_paths_source}" "#include <${old_path}>" included)
  string(FIND "${warnings}" "${old_path} is deprecated: include affine_orb/" warned)
  if(included EQUAL -1 OR warned EQUAL -1)
    message(FATAL_ERROR "${old_path}: included by moved_paths.cpp ${included}, deprecation warning ${warned} (-1: no)")
  endif()
endforeach()
execute_process(COMMAND "${WORK_DIR}/moved_paths" RESULT_VARIABLE rc OUTPUT_VARIABLE moved_out
                OUTPUT_STRIP_TRAILING_WHITESPACE)
if(rc OR NOT moved_out MATCHES "old include paths: [1-9][0-9]* features, [1-9][0-9]* matches")
  message(FATAL_ERROR "moved_paths printed \"${moved_out}\" (exit ${rc})")
endif()
list(LENGTH old_paths old_path_count)
message(STATUS "the ${old_path_count} include paths of 0.1 compile, warn and forward: ${moved_out}")

# The Python module, when the build made one: installed under the prefix's Python directory and
# importable from there.
if(BINARY_DIR)
  file(GLOB python_modules "${PREFIX}/lib/python3*/dist-packages/affine_orb*.so")
  if(EXISTS "${BINARY_DIR}/python" AND NOT python_modules)
    message(FATAL_ERROR "the Python module was built but not installed under ${PREFIX}/lib/python3*/dist-packages")
  endif()
  if(python_modules AND EXISTS /usr/bin/python3)
    list(GET python_modules 0 module)
    get_filename_component(module_dir "${module}" DIRECTORY)
    execute_process(COMMAND "${CMAKE_COMMAND}" -E env "PYTHONPATH=${module_dir}" /usr/bin/python3 -c
                            "import affine_orb; affine_orb.Extractor()" RESULT_VARIABLE rc)
    if(rc)
      message(FATAL_ERROR "the installed Python module does not import")
    endif()
  endif()
endif()
message(STATUS "consumer built with find_package(affine_orb) and with pkg-config against ${PREFIX}: ${out}")
