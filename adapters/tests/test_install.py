"""Tests of adapters/orbslam2/install.sh and adapters/orbslam3/install.sh (common/install_adapter.py), and of
adapters/stella_vslam/install.sh (common/install_stella.py), on
stand-in trees with the layout of each fork: install, reinstall, refresh, uninstall byte for byte,
the refusals, the recovery lines in Tracking.cc, and the installed CMake lines compiling the adapter as
C++17 in a C++11 project (and the recovery lines against the adapter's header).

The stand-in files are written here: each holds only the identifiers the installer looks at (the
namespace in include/System.h, include/Atlas.h for ORB-SLAM3, ComputeKeyPointsOctTree in the fork's
own ORBextractor) and a CMakeLists.txt shaped like the forks' (-std=c++11 in CMAKE_CXX_FLAGS, an
include_directories() block, add_library() listing src/ORBextractor.cc). Run by ctest
(test_adapter_install) with AFFINE_ORB_CMAKE, AFFINE_ORB_CMAKE_GENERATOR and AFFINE_ORB_CXX naming
the build's CMake, generator and C++ compiler, which the compile check uses; without them it is
skipped."""
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

PROJECT = Path(__file__).resolve().parents[2]
BACKUP = ".affine_orb_backup"
# install.sh runs `python3`: this interpreter, not a wrapper that may stand first on PATH (pyenv's).
SCRIPT_ENVIRONMENT = dict(os.environ, PATH=os.pathsep.join([str(Path(sys.executable).parent),
                                                            os.environ.get("PATH", "")]))

CMAKELISTS = """\
cmake_minimum_required(VERSION 3.16)
project({project})

set(CMAKE_CXX_FLAGS "${{CMAKE_CXX_FLAGS}} -Wall -std=c++11")
add_definitions(-DCOMPILEDWITHC11)

find_package(OpenCV 4 REQUIRED COMPONENTS core)

include_directories(
${{PROJECT_SOURCE_DIR}}
${{PROJECT_SOURCE_DIR}}/include
)

set(CMAKE_LIBRARY_OUTPUT_DIRECTORY ${{PROJECT_SOURCE_DIR}}/lib)

add_library(${{PROJECT_NAME}} SHARED
src/System.cc
src/Tracking.cc
src/ORBextractor.cc
src/Frame.cc{headers}
)

target_link_libraries(${{PROJECT_NAME}}
${{OpenCV_LIBS}}
)

add_executable(example_tool src/System.cc)
"""

STOCK_HEADER = """\
// Stand-in for the fork's own extractor header: the identifier its installer recognises.
#pragma once
#include <vector>
#include <opencv2/core.hpp>
namespace {namespace} {{
class ORBextractor {{
 public:
  ORBextractor(int nfeatures, float scaleFactor, int nlevels, int iniThFAST, int minThFAST);
 protected:
  void ComputeKeyPointsOctTree(std::vector<std::vector<cv::KeyPoint> >& allKeypoints);
}};
}}
"""

STOCK_SOURCE = """\
// Stand-in for the fork's own extractor source.
#include "ORBextractor.h"
namespace {namespace} {{
void ORBextractor::ComputeKeyPointsOctTree(std::vector<std::vector<cv::KeyPoint> >&) {{}}
}}
"""

FOREIGN_HEADER = """\
// A different extractor with ORB-SLAM's class name (a learned detector, say).
#pragma once
#include <opencv2/core.hpp>
namespace {namespace} {{
class ORBextractor {{
 public:
  void operator()(cv::InputArray image, cv::InputArray mask, std::vector<cv::KeyPoint>& keypoints,
                  cv::OutputArray descriptors);
}};
}}
"""

FOREIGN_SOURCE = """\
#include "ORBextractor.h"
namespace {namespace} {{
void ORBextractor::operator()(cv::InputArray, cv::InputArray, std::vector<cv::KeyPoint>&, cv::OutputArray) {{}}
}}
"""

# Frame.cc is compiled as C++11 like every fork file that includes ORBextractor.h through Frame.h.
FRAME_HEADER = """\
#pragma once
#include "ORBextractor.h"
namespace {namespace} {{
class Frame {{
 public:
  explicit Frame(ORBextractor* extractor) : mpORBextractorLeft(extractor) {{}}
  int Levels() const;
  ORBextractor* mpORBextractorLeft;
}};
}}
"""

FRAME_SOURCE = """\
#include "Frame.h"
namespace {namespace} {{
int Frame::Levels() const {{ return mpORBextractorLeft->GetLevels(); }}
}}
"""

# The three image entry points with ORB-SLAM's layout (signature line, brace on the next line; ORB-SLAM3
# returns Sophus::SE3f and takes a file name), and the state names the recovery line reads.
TRACKING_SOURCE = """\
#include "ORBextractor.h"
namespace {namespace} {{
class Tracking {{
 public:
  enum eTrackingState {{ NOT_INITIALIZED = 1, OK = 2, RECENTLY_LOST = 3, LOST = 4 }};
  int GrabImageStereo(int left, int right, const double& timestamp);
  int GrabImageRGBD(int rgb, int depth, const double& timestamp);
  int GrabImageMonocular(int image, const double& timestamp);
  eTrackingState mState = NOT_INITIALIZED;
}};

int Tracking::GrabImageStereo(int left, int right, const double &timestamp)
{{
    return left + right + static_cast<int>(timestamp);
}}

int Tracking::GrabImageRGBD(int rgb, int depth,
                            const double &timestamp) {{
    return rgb + depth + static_cast<int>(timestamp);
}}

int Tracking::GrabImageMonocular(int image, const double &timestamp)
{{
    // a comment with a brace {{
    return image + static_cast<int>(timestamp);
}}
}}
"""


def write(path, text, newline="\n"):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(text.replace("\n", newline).encode())


def make_standin(root, fork, newline="\n"):
    """An ORB-SLAM2 or ORB-SLAM3 stand-in tree in root (fork 'orbslam2' or 'orbslam3')."""
    namespace = "ORB_SLAM2" if fork == "orbslam2" else "ORB_SLAM3"
    headers = "" if fork == "orbslam2" else "\ninclude/System.h\ninclude/ORBextractor.h\ninclude/Frame.h"
    write(root / "CMakeLists.txt", CMAKELISTS.format(project=namespace, headers=headers), newline)
    write(root / "include/System.h", "#pragma once\nnamespace %s {\nclass System {};\n}\n" % namespace)
    write(root / "include/Map.h", "#pragma once\nnamespace %s {\nclass Map {};\n}\n" % namespace)
    if fork == "orbslam3":
        write(root / "include/Atlas.h", "#pragma once\nnamespace ORB_SLAM3 {\nclass Atlas {};\n}\n")
    write(root / "include/Frame.h", FRAME_HEADER.format(namespace=namespace))
    write(root / "src/Frame.cc", FRAME_SOURCE.format(namespace=namespace))
    write(root / "src/System.cc", '#include "System.h"\nint main() { return 0; }\n')
    write(root / "src/Tracking.cc", TRACKING_SOURCE.format(namespace=namespace), newline)
    write(root / "include/ORBextractor.h", STOCK_HEADER.format(namespace=namespace))
    write(root / "src/ORBextractor.cc", STOCK_SOURCE.format(namespace=namespace))
    (root / "src/ORBextractor.cc").chmod(0o755)  # a mode the round trip must keep


def snapshot(root):
    """Every file under root (hidden ones included): relative path -> (bytes, mode)."""
    files = {}
    for path in sorted(root.rglob("*")):
        if path.is_file():
            files[path.relative_to(root).as_posix()] = (path.read_bytes(), path.stat().st_mode)
    return files


def mtimes(root):
    return {path: path.stat().st_mtime_ns for path in root.rglob("*") if path.is_file()}


def compile_commands(test, source, build):
    """Configures `source` into `build` with the CMake, compiler and generator of AFFINE_ORB_CMAKE,
    AFFINE_ORB_CXX and AFFINE_ORB_CMAKE_GENERATOR, and returns its compile commands by file name:
    (arguments, directory) each."""
    configure = [os.environ["AFFINE_ORB_CMAKE"], "-S", str(source), "-B", str(build),
                 "-DCMAKE_CXX_COMPILER=" + os.environ["AFFINE_ORB_CXX"], "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON"]
    if os.environ.get("AFFINE_ORB_CMAKE_GENERATOR"):
        configure += ["-G", os.environ["AFFINE_ORB_CMAKE_GENERATOR"]]
    result = subprocess.run(configure, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
    test.assertEqual(result.returncode, 0, result.stdout)
    commands = {}
    for entry in json.loads((build / "compile_commands.json").read_text()):
        arguments = entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])
        commands[Path(entry["file"]).name] = (arguments, entry["directory"])
    return commands


class InstallTest:
    """The checks for one fork; the subclasses below name it."""

    fork = None
    other_fork = None

    def setUp(self):
        self.temporary = tempfile.TemporaryDirectory()
        self.work = Path(self.temporary.name)
        self.tree = self.work / "fork"
        make_standin(self.tree, self.fork)
        self.adapter = PROJECT / "adapters" / self.fork

    def tearDown(self):
        self.temporary.cleanup()

    def run_script(self, *args):
        script = PROJECT / "adapters" / self.fork / "install.sh"
        return subprocess.run([str(script)] + [str(arg) for arg in args], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, universal_newlines=True, env=SCRIPT_ENVIRONMENT)

    def assert_succeeds(self, *args, says):
        result = self.run_script(*args)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertIn(says, result.stdout)
        return result

    def assert_refused(self, tree, says, *options):
        before = snapshot(tree)
        result = self.run_script(*options, tree)
        self.assertEqual(result.returncode, 1, result.stdout + result.stderr)
        self.assertIn(says, result.stderr)
        self.assertEqual(snapshot(tree), before, "a refused run changed the tree")

    def cmake_lines(self):
        return (self.tree / "CMakeLists.txt").read_text().split("\n")

    def test_install_reinstall_uninstall(self):
        original = snapshot(self.tree)
        self.assert_succeeds(self.tree, says="installed affine_orb's adapter")
        for name, relative in (("ORBextractor.h", "include/ORBextractor.h"),
                               ("ORBextractor.cc", "src/ORBextractor.cc")):
            self.assertEqual((self.tree / relative).read_bytes(), (self.adapter / name).read_bytes())
            self.assertEqual((self.tree / BACKUP / relative).read_bytes(), original[relative][0])
            self.assertEqual((self.tree / relative).stat().st_mode, original[relative][1])
        lines = self.cmake_lines()
        begin = lines.index(next(line for line in lines if line.startswith("# >>> affine_orb adapter")))
        end = lines.index("# <<< affine_orb adapter")
        block = lines[begin:end + 1]
        self.assertIn('set(AFFINE_ORB_DIR "%s")' % PROJECT.as_posix(), block)
        self.assertIn('include_directories("${AFFINE_ORB_DIR}/include" "${AFFINE_ORB_DIR}/adapters/common")',
                      block)
        self.assertIn("set_source_files_properties(src/ORBextractor.cc PROPERTIES COMPILE_OPTIONS -std=c++17)",
                      block)
        self.assertEqual(lines[end + 1], "add_library(${PROJECT_NAME} SHARED")
        self.assertEqual("\n".join(lines[:begin] + lines[end + 1:]).encode(), original["CMakeLists.txt"][0])

        installed, times = snapshot(self.tree), mtimes(self.tree)
        self.assert_succeeds(self.tree, says="already installed and up to date")
        self.assertEqual(snapshot(self.tree), installed)
        self.assertEqual(mtimes(self.tree), times, "a second install rewrote files (the fork would rebuild)")

        self.assert_succeeds("--uninstall", self.tree, says="uninstalled")
        self.assertEqual(snapshot(self.tree), original)
        self.assert_succeeds("--uninstall", self.tree, says="not installed; nothing changed")
        self.assertEqual(snapshot(self.tree), original)

    def recovery_lines(self):
        lines = (self.tree / "src/Tracking.cc").read_text().split("\n")
        return [(i, line) for i, line in enumerate(lines) if "SetRecovering" in line]

    def test_recovery_lines(self):
        original = snapshot(self.tree)
        lost = "mState == LOST" if self.fork == "orbslam2" else "mState == LOST || mState == RECENTLY_LOST"
        self.assert_succeeds("--recovery", self.tree,
                             says="ORBextractor::SetRecovering(%s) at the top of 3 GrabImage functions" % lost)
        lines = (self.tree / "src/Tracking.cc").read_text().split("\n")
        found = self.recovery_lines()
        self.assertEqual(len(found), 3)
        for i, line in found:
            # the first statement of a GrabImage function: the line before opens its body
            self.assertTrue(lines[i - 1].rstrip().endswith("{"), lines[i - 1])
            self.assertIn("GrabImage", lines[i - 1] if "Tracking::" in lines[i - 1] else lines[i - 2])
            self.assertEqual(line.split("//")[0].strip(), "ORBextractor::SetRecovering(%s);" % lost)
        without = [line for i, line in enumerate(lines) if i not in {j for j, _ in found}]
        self.assertEqual("\n".join(without).encode(), original["src/Tracking.cc"][0])

        # Again with --recovery, or a plain refresh: nothing changes; --no-recovery removes the lines.
        installed, times = snapshot(self.tree), mtimes(self.tree)
        self.assert_succeeds("--recovery", self.tree, says="already installed and up to date")
        self.assert_succeeds(self.tree, says="already installed and up to date")
        self.assertEqual(snapshot(self.tree), installed)
        self.assertEqual(mtimes(self.tree), times)
        self.assert_succeeds("--no-recovery", self.tree, says="src/Tracking.cc: removed the recovery lines")
        self.assertEqual(self.recovery_lines(), [])
        self.assertEqual((self.tree / "src/Tracking.cc").read_bytes(), original["src/Tracking.cc"][0])

        # Uninstalling removes them with the rest: the fork is back byte for byte.
        self.assert_succeeds("--recovery", self.tree, says="installed")
        self.assert_succeeds("--uninstall", self.tree, says="src/Tracking.cc: removed the recovery lines")
        self.assertEqual(snapshot(self.tree), original)

    def test_recovery_refusals(self):
        tracking = self.tree / "src/Tracking.cc"
        text = tracking.read_text()
        # the 0.1.0 fork line, which the adapter no longer compiles with
        tracking.write_text(text.replace("{\n    return left", "{\n    ORBextractor::SetViewsActive(mState != OK);\n"
                                         "    return left", 1))
        self.assert_refused(self.tree, "calls ORBextractor::SetViewsActive, which the adapter no longer has")
        self.assert_refused(self.tree, "calls ORBextractor::SetViewsActive", "--recovery")
        # a recovery line written by hand
        tracking.write_text(text.replace("{\n    return left", "{\n    ORBextractor::SetRecovering(true);\n"
                                         "    return left", 1))
        self.assert_refused(self.tree, "calls ORBextractor::SetRecovering outside the lines this script manages",
                            "--recovery")
        # no entry point to put the line in
        tracking.write_text("// no GrabImage here\n")
        self.assert_refused(self.tree, "defines no Tracking::GrabImageStereo/RGBD/Monocular", "--recovery")
        tracking.unlink()
        self.assert_refused(self.tree, "has no src/Tracking.cc for the recovery lines", "--recovery")
        result = self.run_script("--recovery", "--uninstall", self.tree)
        self.assertEqual(result.returncode, 2, result.stdout + result.stderr)

    def test_crlf_cmakelists_round_trip(self):
        shutil.rmtree(str(self.tree))
        make_standin(self.tree, self.fork, newline="\r\n")
        original = snapshot(self.tree)
        self.assert_succeeds(self.tree, says="installed")
        text = (self.tree / "CMakeLists.txt").read_bytes()
        self.assertIn(b"# <<< affine_orb adapter\r\nadd_library(", text)
        self.assertNotIn(b"\n", text.replace(b"\r\n", b""))
        self.assert_succeeds("--recovery", self.tree, says="installed")
        text = (self.tree / "src/Tracking.cc").read_bytes()
        self.assertEqual(text.count(b"(install.sh --recovery)\r\n"), 3)
        self.assertNotIn(b"\n", text.replace(b"\r\n", b""))
        self.assert_succeeds("--uninstall", self.tree, says="uninstalled")
        self.assertEqual(snapshot(self.tree), original)

    def test_refresh_after_the_project_changed(self):
        checkout = self.work / "affine_orb"
        (checkout / "adapters" / self.fork).mkdir(parents=True)
        (checkout / "include").symlink_to(PROJECT / "include")
        (checkout / "adapters" / "common").symlink_to(PROJECT / "adapters" / "common")
        for name in ("ORBextractor.h", "ORBextractor.cc"):
            shutil.copy(str(self.adapter / name), str(checkout / "adapters" / self.fork / name))
        original = snapshot(self.tree)
        self.assert_succeeds("--affine-orb", checkout, self.tree, says="installed")
        self.assertIn('set(AFFINE_ORB_DIR "%s")' % checkout.as_posix(), self.cmake_lines())

        changed = (self.adapter / "ORBextractor.cc").read_bytes() + b"// a newer adapter\n"
        (checkout / "adapters" / self.fork / "ORBextractor.cc").write_bytes(changed)
        cmake_before = (self.tree / "CMakeLists.txt").read_bytes()
        self.assert_succeeds("--affine-orb", checkout, self.tree,
                             says="updated src/ORBextractor.cc by adapters/%s/ORBextractor.cc" % self.fork)
        self.assertEqual((self.tree / "src/ORBextractor.cc").read_bytes(), changed)
        self.assertEqual((self.tree / "CMakeLists.txt").read_bytes(), cmake_before)
        self.assertEqual((self.tree / BACKUP / "src/ORBextractor.cc").read_bytes(),
                         original["src/ORBextractor.cc"][0])

        result = self.assert_succeeds(self.tree, says="CMakeLists.txt: updated the affine_orb lines")
        self.assertIn("updated src/ORBextractor.cc", result.stdout)
        self.assertIn('set(AFFINE_ORB_DIR "%s")' % PROJECT.as_posix(), self.cmake_lines())
        self.assertEqual(sum(line.startswith("# >>> affine_orb adapter") for line in self.cmake_lines()), 1)

        self.assert_succeeds("--uninstall", self.tree, says="uninstalled")
        self.assertEqual(snapshot(self.tree), original)

    def test_refuses_what_is_not_this_fork(self):
        empty = self.work / "empty"
        empty.mkdir()
        self.assert_refused(empty, "is not an %s checkout" % self.name)
        self.assert_refused(empty, "is not an %s checkout" % self.name, "--uninstall")
        self.assert_refused(self.tree, "%s is not an affine_orb checkout" % empty, "--affine-orb", empty)
        (self.tree / "src/ORBextractor.cc").unlink()
        self.assert_refused(self.tree, "src/ORBextractor.cc is missing")

        other = self.work / "other"
        make_standin(other, self.other_fork)
        self.assert_refused(other, "use adapters/%s/install.sh" % self.other_fork)
        self.assert_refused(other, "use adapters/%s/install.sh" % self.other_fork, "--uninstall")

    def test_refuses_a_foreign_extractor(self):
        namespace = self.name.replace("-", "_")
        write(self.tree / "include/ORBextractor.h", FOREIGN_HEADER.format(namespace=namespace))
        self.assert_refused(self.tree, "another extractor is installed: include/ORBextractor.h")
        write(self.tree / "src/ORBextractor.cc", FOREIGN_SOURCE.format(namespace=namespace))
        self.assert_refused(self.tree, "another extractor is installed")

        make_standin(self.tree, self.fork)
        original = snapshot(self.tree)
        self.assert_succeeds(self.tree, says="installed")
        write(self.tree / "include/ORBextractor.h", FOREIGN_HEADER.format(namespace=namespace))
        self.assert_refused(self.tree, "another extractor is installed", "--uninstall")
        shutil.copy(str(self.adapter / "ORBextractor.h"), str(self.tree / "include/ORBextractor.h"))
        self.assert_succeeds("--uninstall", self.tree, says="uninstalled")
        self.assertEqual(snapshot(self.tree), original)

    def test_refuses_a_hand_made_install(self):
        for name, relative in (("ORBextractor.h", "include/ORBextractor.h"),
                               ("ORBextractor.cc", "src/ORBextractor.cc")):
            shutil.copy(str(self.adapter / name), str(self.tree / relative))
        self.assert_refused(self.tree, "holds no copy of the fork's own file")
        self.assert_refused(self.tree, "holds no copy of the fork's own file", "--uninstall")

        make_standin(self.tree, self.fork)
        cmake = self.tree / "CMakeLists.txt"
        cmake.write_text(cmake.read_text().replace(
            "add_library(", "include_directories(${AFFINE_ORB}/include)\nadd_library(", 1))
        self.assert_refused(self.tree, "line 16, mentions affine_orb outside the lines this script manages")

    def test_refuses_damaged_markers_and_a_missing_library(self):
        self.assert_succeeds(self.tree, says="installed")
        cmake = self.tree / "CMakeLists.txt"
        cmake.write_text(cmake.read_text().replace("# <<< affine_orb adapter\n", ""))
        self.assert_refused(self.tree, "are damaged (1 begin and 0 end markers)")
        self.assert_refused(self.tree, "are damaged", "--uninstall")

        make_standin(self.tree, self.fork)
        shutil.rmtree(str(self.tree / BACKUP))
        cmake.write_text(re.sub(r"add_library\(\$\{PROJECT_NAME\}.*?\n\)\n",
                                "file(GLOB sources src/*.cc)\nadd_library(${PROJECT_NAME} SHARED ${sources})\n",
                                cmake.read_text(), count=1, flags=re.DOTALL))
        self.assert_refused(self.tree, "has no add_library(...) that compiles src/ORBextractor.cc")

    def write_cache(self, source):
        """A build/CMakeCache.txt in the fork as CMake writes it for the source tree `source`."""
        write(self.tree / "build/CMakeCache.txt",
              "# This is the CMakeCache file.\nCMAKE_BUILD_TYPE:STRING=Release\n"
              "%s_BINARY_DIR:STATIC=%s/build\n%s_SOURCE_DIR:STATIC=%s\n"
              "CMAKE_CACHEFILE_DIR:INTERNAL=%s/build\nCMAKE_HOME_DIRECTORY:INTERNAL=%s\n"
              % (self.name.replace("-", "_"), source, self.name.replace("-", "_"), source, source, source))

    def test_refuses_a_build_folder_of_another_tree(self):
        # Configured here (also through a link to the tree): installs as usual.
        self.write_cache(self.tree)
        self.assert_succeeds(self.tree, says="installed")
        self.assert_succeeds("--uninstall", self.tree, says="uninstalled")
        link = self.work / "link"
        link.symlink_to(self.tree)
        self.write_cache(link)
        self.assert_succeeds(self.tree, says="installed")
        self.assert_succeeds("--uninstall", self.tree, says="uninstalled")

        # Copied from a built tree: the cache names the original; install and uninstall change nothing.
        stock = self.work / "stock"
        self.write_cache(stock)
        says = "build/CMakeCache.txt was configured for another source tree (CMAKE_HOME_DIRECTORY=%s" % stock
        self.assert_refused(self.tree, says)
        self.assert_refused(self.tree, "rm -rf %s" % (self.tree / "build"), "--recovery")
        self.assert_succeeds("--ignore-build-dir", self.tree, says="installed")
        self.assert_refused(self.tree, says, "--uninstall")
        self.assert_succeeds("--ignore-build-dir", "--uninstall", self.tree, says="uninstalled")

        # Only the project's source directory names the original (a cache edited by hand).
        self.write_cache(self.tree)
        cache = self.tree / "build/CMakeCache.txt"
        cache.write_text(cache.read_text().replace("_SOURCE_DIR:STATIC=%s" % self.tree, "_SOURCE_DIR:STATIC=%s" % stock))
        self.assert_refused(self.tree, "(%s_SOURCE_DIR=%s" % (self.name.replace("-", "_"), stock))

        # Removed as the message says: installs.
        shutil.rmtree(str(self.tree / "build"))
        self.assert_succeeds(self.tree, says="installed")

    @unittest.skipUnless(os.environ.get("AFFINE_ORB_CMAKE") and os.environ.get("AFFINE_ORB_CXX"),
                         "AFFINE_ORB_CMAKE and AFFINE_ORB_CXX name no CMake and compiler")
    def test_refuses_a_copy_of_a_configured_fork(self):
        # The user's way: configure the fork in its build/, copy the whole tree with its build/.
        stock = self.work / "stock"
        shutil.move(str(self.tree), str(stock))
        configure = [os.environ["AFFINE_ORB_CMAKE"], "-S", str(stock), "-B", str(stock / "build"),
                     "-DCMAKE_CXX_COMPILER=" + os.environ["AFFINE_ORB_CXX"]]
        if os.environ.get("AFFINE_ORB_CMAKE_GENERATOR"):
            configure += ["-G", os.environ["AFFINE_ORB_CMAKE_GENERATOR"]]
        result = subprocess.run(configure, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
        self.assertEqual(result.returncode, 0, result.stdout)
        shutil.copytree(str(stock), str(self.tree), symlinks=True)
        self.assert_refused(self.tree, "was configured for another source tree")
        self.assert_succeeds(stock, says="installed")

    @unittest.skipUnless(os.environ.get("AFFINE_ORB_CMAKE") and os.environ.get("AFFINE_ORB_CXX"),
                         "AFFINE_ORB_CMAKE and AFFINE_ORB_CXX name no CMake and compiler")
    def test_installed_fork_compiles_the_adapter_as_cxx17(self):
        self.assert_succeeds("--recovery", self.tree, says="installed")
        commands = compile_commands(self, self.tree, self.work / "build")
        for name, standard in (("ORBextractor.cc", "-std=c++17"), ("Frame.cc", "-std=c++11"),
                               ("Tracking.cc", "-std=c++11")):
            arguments, directory = commands[name]
            self.assertEqual([argument for argument in arguments if argument.startswith("-std=")][-1], standard,
                             "%s: %s" % (name, " ".join(arguments)))
            # The compiler with the fork's own flags for this file: the adapter's headers are found, the
            # adapter compiles as C++17 and the fork's C++11 files compile with the adapter's header.
            result = subprocess.run(arguments + ["-fsyntax-only"], cwd=directory, stdout=subprocess.PIPE,
                                    stderr=subprocess.STDOUT, universal_newlines=True)
            self.assertEqual(result.returncode, 0, result.stdout)


class OrbSlam2(InstallTest, unittest.TestCase):
    fork, other_fork, name = "orbslam2", "orbslam3", "ORB-SLAM2"


class OrbSlam3(InstallTest, unittest.TestCase):
    fork, other_fork, name = "orbslam3", "orbslam2", "ORB-SLAM3"


STELLA_HEADER = """\
namespace stella_vslam {
namespace feature {
class orb_extractor {
public:
    std::vector<cv::Mat> image_pyramid_;
};
} // namespace feature
} // namespace stella_vslam
"""
STELLA_SOURCE = "// stand-in\nstd::vector<cv::KeyPoint> orb_extractor::distribute_keypoints() {}\n"
STELLA_CMAKE = "target_sources(${PROJECT_NAME}\n    PRIVATE\n    ${CMAKE_CURRENT_SOURCE_DIR}/orb_extractor.cc)\n"
STELLA_SYSTEM = """\
int system_stand_in() {
    extractor_left_ = new feature::orb_extractor(orb_params_, min_size, desc_type, mask_rectangles);
    if (camera_->setup_type_ == camera::setup_type_t::Stereo) {
        extractor_right_ = new feature::orb_extractor(orb_params_, min_size, desc_type, mask_rectangles);
    }
    return 0;
}

int feed_frame_stand_in() {
    const auto cam_pose_wc = tracker_->feed_frame(frm);
    return 0;
}
"""
STELLA_SWITCH = "extractor->set_affine_orb_recovering(tracker_->tracking_state_ == tracker_state_t::Lost);"


class StellaVslam(unittest.TestCase):
    """adapters/stella_vslam/install.sh (common/install_stella.py) on a stand-in stella_vslam tree."""

    def setUp(self):
        self.root = Path(tempfile.mkdtemp(prefix="affine_orb_stella_"))
        self.addCleanup(shutil.rmtree, str(self.root))
        feature = self.root / "src/stella_vslam/feature"
        write(feature / "orb_extractor.h", STELLA_HEADER)
        write(feature / "orb_extractor.cc", STELLA_SOURCE)
        write(feature / "CMakeLists.txt", STELLA_CMAKE)
        write(self.root / "src/stella_vslam/system.cc", STELLA_SYSTEM)

    def run_script(self, *args):
        return subprocess.run(["sh", str(PROJECT / "adapters/stella_vslam/install.sh")] + list(args),
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                              env=SCRIPT_ENVIRONMENT)

    def test_install_reinstall_uninstall(self):
        before = snapshot(self.root)
        self.assertEqual(self.run_script(str(self.root)).returncode, 0)
        feature = self.root / "src/stella_vslam/feature"
        self.assertEqual((feature / "orb_extractor.cc").read_bytes(),
                         (PROJECT / "adapters/stella_vslam/orb_extractor.cc").read_bytes())
        header = (feature / "orb_extractor.h").read_text()
        added = [line for line in header.splitlines() if line not in STELLA_HEADER.splitlines()]
        self.assertEqual([line.strip() for line in added if not line.strip().startswith("//")],
                         ["void configure_affine_orb(const YAML::Node& feature, bool recovery_hook);",
                          "void set_affine_orb_recovering(bool recovering);"])
        self.assertLess(header.index("image_pyramid_;"), header.index("configure_affine_orb"))
        self.assertLess(header.index("set_affine_orb_recovering"), header.index("};"))
        self.assertEqual(self.configure_calls(), ["false", "false"])
        self.assertNotIn(STELLA_SWITCH, (self.root / "src/stella_vslam/system.cc").read_text())
        self.assertIn(str(PROJECT / "adapters" / "common"), (feature / "CMakeLists.txt").read_text())
        installed = snapshot(self.root)
        again = self.run_script(str(self.root))
        self.assertEqual(again.returncode, 0)
        self.assertIn("nothing to do", again.stdout)
        self.assertEqual(snapshot(self.root), installed)
        self.assertEqual(self.run_script("--uninstall", str(self.root)).returncode, 0)
        self.assertEqual(snapshot(self.root), before)

    def configure_calls(self):
        """The second argument of each configure_affine_orb() call in system.cc, after the construction
        of the extractor it configures."""
        system = (self.root / "src/stella_vslam/system.cc").read_text().splitlines()
        calls = []
        for side in ("left", "right"):
            construction = [i for i, line in enumerate(system) if line.strip().startswith("extractor_%s_ = new" % side)]
            self.assertEqual(len(construction), 1)
            call = system[construction[0] + 1].strip()
            prefix = 'extractor_%s_->configure_affine_orb(util::yaml_optional_ref(cfg->yaml_node_, "Feature"), ' % side
            self.assertTrue(call.startswith(prefix) and call.endswith(");  // affine_orb adapter"), call)
            calls.append(call[len(prefix):-len(");  // affine_orb adapter")])
        return calls

    def test_recovery_switch_added_kept_and_removed(self):
        before = snapshot(self.root)
        system = self.root / "src/stella_vslam/system.cc"
        self.assertEqual(self.run_script("--recovery", str(self.root)).returncode, 0)
        self.assertEqual(self.configure_calls(), ["true", "true"])
        lines = system.read_text().splitlines()
        tracked = [i for i, line in enumerate(lines) if "tracker_->feed_frame(frm);" in line]
        self.assertEqual(len(tracked), 1)
        self.assertEqual(lines[tracked[0] + 2].strip(), "if (extractor) " + STELLA_SWITCH)
        self.assertEqual(system.read_text().count(STELLA_SWITCH), 1)
        recovering = snapshot(self.root)
        again = self.run_script(str(self.root))  # a plain install keeps the switch
        self.assertIn("nothing to do", again.stdout)
        self.assertEqual(snapshot(self.root), recovering)
        self.assertEqual(self.run_script("--no-recovery", str(self.root)).returncode, 0)
        self.assertEqual(self.configure_calls(), ["false", "false"])
        self.assertNotIn(STELLA_SWITCH, system.read_text())
        self.assertEqual(self.run_script("--recovery", str(self.root)).returncode, 0)
        self.assertEqual(snapshot(self.root), recovering)
        self.assertEqual(self.run_script("--uninstall", str(self.root)).returncode, 0)
        self.assertEqual(snapshot(self.root), before)

    def test_refuses_what_it_does_not_know(self):
        self.assertEqual(self.run_script(str(self.root / "src")).returncode, 1)
        source = self.root / "src/stella_vslam/feature/orb_extractor.cc"
        write(source, "// another extractor\n")
        before = snapshot(self.root)
        refused = self.run_script(str(self.root))
        self.assertEqual(refused.returncode, 1)
        self.assertIn("neither stella's own extractor", refused.stderr)
        self.assertEqual(snapshot(self.root), before)
        write(source, STELLA_SOURCE)
        system = self.root / "src/stella_vslam/system.cc"
        for text, complaint in ((STELLA_SYSTEM.split("\n\n")[1], "does not construct extractor_left_"),
                                (STELLA_SYSTEM.split("\n\n")[0], "no single `const auto cam_pose_wc")):
            write(system, text)
            before = snapshot(self.root)
            refused = self.run_script(str(self.root))
            self.assertEqual(refused.returncode, 1)
            self.assertIn(complaint, refused.stderr)
            self.assertEqual(snapshot(self.root), before)

    def test_installs_over_an_install_without_the_yaml_lines(self):
        # An install by the adapter before configure_affine_orb() changed orb_extractor.cc and the
        # CMake lines only: installing again adds the two files' lines, --uninstall restores all.
        before = snapshot(self.root)
        feature = self.root / "src/stella_vslam/feature"
        write(self.root / ".affine_orb_backup/src/stella_vslam/feature/orb_extractor.cc", STELLA_SOURCE)
        write(self.root / ".affine_orb_backup/src/stella_vslam/feature/CMakeLists.txt", STELLA_CMAKE)
        write(feature / "orb_extractor.cc", (PROJECT / "adapters/stella_vslam/orb_extractor.cc").read_text())
        self.assertEqual(self.run_script(str(self.root)).returncode, 0)
        self.assertIn("configure_affine_orb", (feature / "orb_extractor.h").read_text())
        self.assertIn("configure_affine_orb", (self.root / "src/stella_vslam/system.cc").read_text())
        self.assertEqual(self.run_script("--uninstall", str(self.root)).returncode, 0)
        self.assertEqual(snapshot(self.root), before)

    @unittest.skipUnless(os.environ.get("AFFINE_ORB_CMAKE") and os.environ.get("AFFINE_ORB_CXX"),
                         "AFFINE_ORB_CMAKE and AFFINE_ORB_CXX name no CMake and compiler")
    def test_installed_tree_compiles_the_adapter_alone_as_cxx17(self):
        # stella's layout: CMAKE_CXX_STANDARD 11 at the top, the library target made in
        # src/stella_vslam/ and raised to C++14 by what it links (g2o 20230223's targets ask for
        # cxx_std_14), feature/ a subdirectory adding orb_extractor.cc to it.
        write(self.root / "CMakeLists.txt", "cmake_minimum_required(VERSION 3.18)\nproject(stella_vslam CXX)\n"
              "set(CMAKE_CXX_STANDARD 11)\nadd_subdirectory(src/stella_vslam)\n")
        write(self.root / "src/stella_vslam/CMakeLists.txt",
              "add_library(${PROJECT_NAME} SHARED ${CMAKE_CURRENT_SOURCE_DIR}/system.cc)\n"
              "target_compile_features(${PROJECT_NAME} PUBLIC cxx_std_14)\nadd_subdirectory(feature)\n")
        self.assertEqual(self.run_script(str(self.root)).returncode, 0)
        commands = compile_commands(self, self.root, self.root / "build")
        common = str(PROJECT / "adapters" / "common")
        for name, standard, adapter_includes in (("orb_extractor.cc", "-std=gnu++17", True),
                                                 ("system.cc", "-std=gnu++14", False)):
            arguments = commands[name][0]
            line = " ".join(arguments)
            self.assertEqual([argument for argument in arguments if argument.startswith("-std=")][-1], standard, line)
            self.assertEqual(common in line, adapter_includes, line)


if __name__ == "__main__":
    unittest.main()
