#!/usr/bin/env python3
"""Installs affine_orb's ORBextractor adapter into an ORB-SLAM2 or ORB-SLAM3 checkout, or removes it.

adapters/orbslam2/install.sh and adapters/orbslam3/install.sh run this file with their fork's name
as first argument; `--help` explains the rest. Python 3.6 or later, standard library only.

What an install does to the fork (FORK below), and what --uninstall undoes byte for byte:
- the fork's own include/ORBextractor.h and src/ORBextractor.cc are saved in FORK/.affine_orb_backup/
  and replaced by adapters/<fork>/ORBextractor.{h,cc} of the affine_orb checkout;
- FORK/CMakeLists.txt gets, just before the add_library() that compiles src/ORBextractor.cc, a block
  of lines between two marker comments: the checkout's include/ and adapters/common/ on the include
  path, and src/ORBextractor.cc compiled as C++17;
- nothing at all when FORK/build/CMakeCache.txt was configured for another source tree (a fork copied
  with `cp -a` from a built one): `make` in that build/ would rebuild the original tree, and the
  copy's programs would still load the original's library. The refusal says to remove build/ and
  configure afresh; --ignore-build-dir goes ahead anyway (for a user who builds elsewhere);
- with --recovery, FORK/src/Tracking.cc gets one marked line at the top of each
  Tracking::GrabImage{Stereo,RGBD,Monocular}: ORBextractor::SetRecovering(<tracking is lost>), so that
  frames are extracted with the adapter's recovery options while tracking is lost (adapters/README.md,
  "Recovery mode"). --no-recovery removes those lines; a plain install leaves them as they are.

Why C++17 for that one file only, while ORB-SLAM sets -std=c++11 for everything: raising the whole
fork changes how ORB-SLAM's own code compiles (GCC 12 in strict -std=c++17 rejects ORB-SLAM2's
LoopClosing.h map allocator, and ORB-SLAM2 built as C++11 against a g2o built as C++17 crashed in its
first bundle adjustment, probably Eigen allocating aligned types differently; see adapters/README.md).
The adapter's translation unit includes no Eigen and no ORB-SLAM header but its own ORBextractor.h,
which is valid C++11; what crosses the boundary (std::vector of cv::KeyPoint and cv::Mat,
cv::InputArray) has the same layout in both modes: libstdc++'s ABI does not depend on -std. A -std
option set on the source file comes after CMAKE_CXX_FLAGS on the command line, so it wins (the test
checks the order in the compile command).

Recognition (the files are read, nothing is built):
- the fork: include/System.h declares `namespace ORB_SLAM2` / `namespace ORB_SLAM3`, and ORB-SLAM3
  alone has include/Atlas.h;
- the extractor: affine_orb's adapter files include "affine_orb_adapter/..." (the header options.hpp,
  the source core.hpp), which every version of the adapter does; ORB-SLAM2/3's own extractor
  declares and defines ORBextractor::ComputeKeyPointsOctTree, which the adapter does not; a file that
  is neither is another extractor, and the script leaves such a tree alone.
"""

import argparse
import os
import re
import shutil
import sys
from pathlib import Path

PROJECT = Path(__file__).resolve().parents[2]
BACKUP_DIR = ".affine_orb_backup"
HEADER = "include/ORBextractor.h"
SOURCE = "src/ORBextractor.cc"
BEGIN_MARKER = "# >>> affine_orb adapter"
END_MARKER = "# <<< affine_orb adapter"

TRACKING = "src/Tracking.cc"
RECOVERY_MARKER = "// affine_orb recovery mode (install.sh --recovery)"

# "lost": the tracking states in which the previous frame left tracking lost (ORB-SLAM3 first
# enters RECENTLY_LOST, where it still predicts the pose from IMU or the motion model, then LOST).
FORKS = {
    "orbslam2": {"name": "ORB-SLAM2", "namespace": "ORB_SLAM2", "lost": "mState == LOST"},
    "orbslam3": {"name": "ORB-SLAM3", "namespace": "ORB_SLAM3", "lost": "mState == LOST || mState == RECENTLY_LOST"},
}

ADAPTER_INCLUDE = re.compile(rb'^[ \t]*#[ \t]*include[ \t]*["<]affine_orb_adapter/', re.MULTILINE)
STOCK_IDENTIFIER = re.compile(rb"\bComputeKeyPointsOctTree\b")
NAMESPACE = re.compile(rb"^[ \t]*namespace[ \t]+(ORB_SLAM[23])\b", re.MULTILINE)
ADD_LIBRARY = re.compile(r"^\s*add_library\s*\(", re.IGNORECASE)
GRAB_IMAGE = re.compile(r"^[^;/]*\bTracking::GrabImage(Stereo|RGBD|Monocular)\s*\(")


BUILD_CACHE = "build/CMakeCache.txt"
# CMakeCache.txt entries that name the source tree a build folder was configured for: the top-level
# source directory, and each project()'s <Project>_SOURCE_DIR (inside that tree).
CACHE_HOME = re.compile(r"^CMAKE_HOME_DIRECTORY:INTERNAL=(.*)$", re.MULTILINE)
CACHE_SOURCE_DIR = re.compile(r"^(\w+)_SOURCE_DIR:STATIC=(.*)$", re.MULTILINE)


class Refusal(Exception):
    """The tree is not one this script may change; the message says why and what to do."""


def script_name(fork):
    return "adapters/%s/install.sh" % fork


def fork_kind(tree):
    """'orbslam2', 'orbslam3' or None, from include/System.h's namespace and include/Atlas.h."""
    system = tree / "include" / "System.h"
    if not system.is_file():
        return None
    namespace = NAMESPACE.search(system.read_bytes())
    if (tree / "include" / "Atlas.h").is_file() or (namespace and namespace.group(1) == b"ORB_SLAM3"):
        return "orbslam3"
    if namespace:
        return "orbslam2"
    return None


def check_fork(tree, fork):
    """Refuses a tree that is not a checkout of `fork` with the files the install replaces."""
    name = FORKS[fork]["name"]
    if not tree.is_dir():
        raise Refusal("%s is not a directory" % tree)
    kind = fork_kind(tree)
    if kind is None:
        raise Refusal("%s is not an %s checkout: no include/System.h declaring namespace %s"
                      % (tree, name, FORKS[fork]["namespace"]))
    if kind != fork:
        raise Refusal("%s is an %s checkout, not %s: use %s"
                      % (tree, FORKS[kind]["name"], name, script_name(kind)))
    for path in ("CMakeLists.txt", HEADER, SOURCE):
        if not (tree / path).is_file():
            raise Refusal("%s is not an %s checkout: %s is missing" % (tree, name, path))


def same_or_inside(path, tree):
    """Whether `path` (as CMake cached it) is `tree` or a folder inside it, links resolved."""
    resolved = Path(path).resolve()
    return resolved == tree or tree in resolved.parents


def check_build_dir(tree):
    """Refuses a fork whose build/CMakeCache.txt was configured for another source tree (the fork
    copied with cp -a from a built one): `make` there rebuilds the original, not this tree."""
    cache = tree / BUILD_CACHE
    if not cache.is_file():
        return
    text = cache.read_text(errors="replace")
    named = [("CMAKE_HOME_DIRECTORY", match.group(1).strip()) for match in CACHE_HOME.finditer(text)]
    named += [(match.group(1) + "_SOURCE_DIR", match.group(2).strip()) for match in CACHE_SOURCE_DIR.finditer(text)]
    foreign = [(entry, path) for entry, path in named if path and not same_or_inside(path, tree)]
    if foreign:
        entry, path = foreign[0]
        raise Refusal("%s was configured for another source tree (%s=%s; a copy of a built fork?): "
                      "`make` there would rebuild %s, and this tree's programs would load its library. "
                      "Remove it and configure afresh (rm -rf %s; mkdir %s; cd %s; cmake .. "
                      "-DCMAKE_BUILD_TYPE=Release), then run this again; --ignore-build-dir goes ahead "
                      "without that" % (cache, entry, path, path, tree / "build", tree / "build",
                                        tree / "build"))


def check_project(project, fork):
    """Refuses a directory that is not an affine_orb checkout with the fork's adapter."""
    for path in ("include/affine_orb", "adapters/common/affine_orb_adapter"):
        if not (project / path).is_dir():
            raise Refusal("%s is not an affine_orb checkout: %s is missing" % (project, path))
    for name in ("ORBextractor.h", "ORBextractor.cc"):
        if not (project / "adapters" / fork / name).is_file():
            raise Refusal("%s is not an affine_orb checkout: adapters/%s/%s is missing" % (project, fork, name))
    # The path goes into a quoted CMake argument, where these characters would change its meaning.
    if re.search(r'["\\$;\n]', str(project)):
        raise Refusal('the affine_orb path %s contains one of " \\ $ ; or a line break, which CMake '
                      "would not read back as this path: move or link the checkout elsewhere" % project)


def classify(data, stock_identifier=STOCK_IDENTIFIER):
    """'adapter' (affine_orb's), 'stock' (the fork's own: `stock_identifier` matches, ORB-SLAM's by
    default) or 'other', from a file's bytes."""
    if ADAPTER_INCLUDE.search(data):
        return "adapter"
    if stock_identifier.search(data):
        return "stock"
    return "other"


def write_file(path, data, mode_from=None):
    """Replaces `path` by `data` atomically, with the permissions of `mode_from` (default: `path`'s).

    The file gets a fresh modification time, so that make or ninja rebuild what depends on it."""
    mode_from = mode_from or path
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(path.name + ".affine_orb_tmp")
    temporary.write_bytes(data)
    if mode_from.exists():
        shutil.copymode(str(mode_from), str(temporary))
    os.replace(str(temporary), str(path))


class LinesFile:
    """A fork's text file as lines, the newline style and any bytes kept as they are. `original` is
    None for a file that does not exist; nothing is written to it then."""

    def __init__(self, path):
        self.path = path
        self.original = path.read_bytes() if path.is_file() else None
        text = (self.original or b"").decode("utf-8", "surrogateescape")
        self.lines = text.split("\n")  # the last element is what follows the final line break
        self.line_end = "\r" if self.lines[0].endswith("\r") else ""

    def text(self):
        return "\n".join(self.lines).encode("utf-8", "surrogateescape")

    def save_if_changed(self):
        data = self.text()
        if self.original is None or data == self.original:
            return False
        write_file(self.path, data)
        return True


class CMakeLists(LinesFile):
    """The fork's CMakeLists.txt and the marked block this script manages in it."""

    def block(self):
        """(first, last) line index of the marked block, or None; refuses a damaged or repeated one."""
        begins = [i for i, line in enumerate(self.lines) if line.strip().startswith(BEGIN_MARKER)]
        ends = [i for i, line in enumerate(self.lines) if line.strip().startswith(END_MARKER)]
        if not begins and not ends:
            return None
        if len(begins) != 1 or len(ends) != 1 or ends[0] < begins[0]:
            raise Refusal("%s: the lines between '%s' and '%s' are damaged (%d begin and %d end markers); "
                          "remove the affine_orb lines by hand and run this again"
                          % (self.path, BEGIN_MARKER, END_MARKER, len(begins), len(ends)))
        return begins[0], ends[0]

    def check_no_foreign_lines(self, block):
        """Refuses affine_orb lines outside the marked block (added by hand or by another tool)."""
        for i, line in enumerate(self.lines):
            if block and block[0] <= i <= block[1]:
                continue
            if "affine_orb" in line.lower():
                raise Refusal("%s, line %d, mentions affine_orb outside the lines this script manages: "
                              "%s\nremove those lines and run this again" % (self.path, i + 1, line.strip()))

    def library_line(self):
        """Index of the add_library( line whose call lists src/ORBextractor.cc."""
        for i, line in enumerate(self.lines):
            if not ADD_LIBRARY.match(line):
                continue
            call, depth = "", 0
            for following in self.lines[i:]:
                code = following.split("#", 1)[0]
                call += code + "\n"
                depth += code.count("(") - code.count(")")
                if depth <= 0:
                    break
            if SOURCE in call:
                return i
        raise Refusal("%s has no add_library(...) that compiles %s; add the lines of adapters/README.md "
                      "by hand" % (self.path, SOURCE))

    def block_lines(self, fork, project):
        lines = [
            "%s: added by affine_orb's %s, removed by its --uninstall" % (BEGIN_MARKER, script_name(fork)),
            "# include/ORBextractor.h and src/ORBextractor.cc are affine_orb's adapter (the fork's own are",
            "# in %s/). src/ORBextractor.cc alone is compiled as C++17: it includes no ORB-SLAM" % BACKUP_DIR,
            "# header but ORBextractor.h (valid C++11) and no Eigen, so the rest keeps the fork's standard.",
            'set(AFFINE_ORB_DIR "%s")' % project.as_posix(),
            'include_directories("${AFFINE_ORB_DIR}/include" "${AFFINE_ORB_DIR}/adapters/common")',
            "set_source_files_properties(%s PROPERTIES COMPILE_OPTIONS -std=c++17)" % SOURCE,
            END_MARKER,
        ]
        return [line + self.line_end for line in lines]


class Tracking(LinesFile):
    """The fork's src/Tracking.cc and the recovery lines this script manages in it."""

    def __init__(self, tree, fork):
        super().__init__(tree / TRACKING)
        self.fork = fork

    def check(self):
        """Refuses fork lines the adapter no longer compiles with, or recovery lines added by hand."""
        for i, line in enumerate(self.lines):
            if "SetViewsActive" in line:
                raise Refusal("%s, line %d, calls ORBextractor::SetViewsActive, which the adapter no longer has "
                              "(the recovery mode replaces it): remove that line; --recovery adds the "
                              "replacement" % (self.path, i + 1))
            if "SetRecovering" in line and RECOVERY_MARKER not in line:
                raise Refusal("%s, line %d, calls ORBextractor::SetRecovering outside the lines this script "
                              "manages: remove it and run this again with --recovery" % (self.path, i + 1))

    def marked(self):
        return [i for i, line in enumerate(self.lines) if RECOVERY_MARKER in line]

    def recovery_line(self):
        return "    ORBextractor::SetRecovering(%s);  %s%s" % (FORKS[self.fork]["lost"], RECOVERY_MARKER, self.line_end)

    def add_recovery(self):
        """Puts the recovery line after the opening brace of each GrabImage function; returns how many
        functions got it. Refuses a Tracking.cc without such a function."""
        for i in reversed(self.marked()):
            del self.lines[i]
        openings = []
        i = 0
        while i < len(self.lines):
            if GRAB_IMAGE.match(self.lines[i]):
                j = next((k for k in range(i, len(self.lines)) if "{" in self.lines[k].split("//", 1)[0]), None)
                if j is None:
                    break
                openings.append(j)
                i = j
            i += 1
        if not openings:
            raise Refusal("%s defines no Tracking::GrabImageStereo/RGBD/Monocular: add the line "
                          "ORBextractor::SetRecovering(%s); at the top of your fork's image entry points "
                          "by hand (adapters/README.md, \"Recovery mode\")" % (self.path, FORKS[self.fork]["lost"]))
        for j in reversed(openings):
            self.lines.insert(j + 1, self.recovery_line())
        return len(openings)

    def remove_recovery(self):
        for i in reversed(self.marked()):
            del self.lines[i]


def read_state(tree, fork):
    """Each replaced file: its relative path, its bytes and kind, and its backup's bytes (or None).

    Refuses another extractor, the adapter without the fork's own file saved (copied by hand), and a
    backup that is not the fork's own file."""
    name = FORKS[fork]["name"]
    state = []
    for relative in (HEADER, SOURCE):
        data = (tree / relative).read_bytes()
        backup = tree / BACKUP_DIR / relative
        entry = {
            "path": relative,
            "data": data,
            "kind": classify(data),
            "backup": backup.read_bytes() if backup.is_file() else None,
        }
        if entry["kind"] == "other":
            raise Refusal("%s: another extractor is installed: %s is neither %s's own ORBextractor "
                          "(ComputeKeyPointsOctTree) nor affine_orb's adapter; restore the fork's own file "
                          "(e.g. git checkout -- %s %s) and run this again"
                          % (tree, relative, name, HEADER, SOURCE))
        if entry["kind"] == "adapter" and entry["backup"] is None:
            raise Refusal("%s: %s is affine_orb's adapter, but %s/ holds no copy of the fork's own file "
                          "(copied by hand?); restore the fork's own files (e.g. git checkout -- %s %s) and "
                          "remove any affine_orb lines from CMakeLists.txt"
                          % (tree, relative, BACKUP_DIR, HEADER, SOURCE))
        if entry["backup"] is not None and classify(entry["backup"]) != "stock":
            raise Refusal("%s: %s/%s is not %s's own ORBextractor; remove %s/ once the fork's own files "
                          "are back in place" % (tree, BACKUP_DIR, relative, name, BACKUP_DIR))
        state.append(entry)
    return state


def report(tree, changes, done, nothing):
    """Prints each change and then `done`, or `nothing` when nothing changed."""
    for change in changes:
        print("%s: %s" % (tree, change))
    print("%s: %s" % (tree, done if changes else nothing))


def install(tree, fork, project, recovery=None, ignore_build_dir=False):
    """recovery: True adds the recovery lines to src/Tracking.cc, False removes them, None leaves them."""
    check_fork(tree, fork)
    if not ignore_build_dir:
        check_build_dir(tree)
    check_project(project, fork)
    cmake = CMakeLists(tree / "CMakeLists.txt")
    block = cmake.block()
    cmake.check_no_foreign_lines(block)
    anchor = cmake.library_line() if block is None else None
    state = read_state(tree, fork)
    tracking = Tracking(tree, fork)
    if recovery and tracking.original is None:
        raise Refusal("%s has no %s for the recovery lines" % (tree, TRACKING))
    tracking.check()
    functions = tracking.add_recovery() if recovery else 0
    if recovery is False:
        tracking.remove_recovery()

    changes = []
    for entry in state:  # the fork's own files are saved before anything is replaced
        if entry["kind"] == "stock" and entry["backup"] != entry["data"]:
            write_file(tree / BACKUP_DIR / entry["path"], entry["data"], mode_from=tree / entry["path"])
            changes.append("saved the fork's own %s in %s/" % (entry["path"], BACKUP_DIR))
    for entry in state:
        adapter = (project / "adapters" / fork / Path(entry["path"]).name).read_bytes()
        if entry["data"] != adapter:
            write_file(tree / entry["path"], adapter)
            verb = "replaced" if entry["kind"] == "stock" else "updated"
            changes.append("%s %s by adapters/%s/%s" % (verb, entry["path"], fork, Path(entry["path"]).name))
    lines = cmake.block_lines(fork, project)
    if block is None:
        cmake.lines[anchor:anchor] = lines
        changes.append("CMakeLists.txt: added the affine_orb lines before add_library() (line %d)" % (anchor + 1))
    else:
        cmake.lines[block[0]:block[1] + 1] = lines
    if cmake.save_if_changed() and block is not None:
        changes.append("CMakeLists.txt: updated the affine_orb lines (AFFINE_ORB_DIR %s)" % project)
    if tracking.save_if_changed():
        changes.append("%s: %s" % (TRACKING, "ORBextractor::SetRecovering(%s) at the top of %d GrabImage "
                                               "functions" % (FORKS[fork]["lost"], functions) if recovery
                                   else "removed the recovery lines"))

    report(tree, changes,
           "installed affine_orb's adapter (affine_orb: %s); rebuild the fork, e.g. cd build && make; "
           "%s --uninstall %s restores it" % (project, script_name(fork), tree),
           "affine_orb's adapter is already installed and up to date (affine_orb: %s); nothing changed" % project)


def uninstall(tree, fork, ignore_build_dir=False):
    check_fork(tree, fork)
    if not ignore_build_dir:
        check_build_dir(tree)
    cmake = CMakeLists(tree / "CMakeLists.txt")
    block = cmake.block()
    state = read_state(tree, fork)
    tracking = Tracking(tree, fork)

    changes = []
    tracking.remove_recovery()
    if tracking.save_if_changed():
        changes.append("%s: removed the recovery lines" % TRACKING)
    if block is not None:
        del cmake.lines[block[0]:block[1] + 1]
        cmake.save_if_changed()
        changes.append("CMakeLists.txt: removed the affine_orb lines")
    for entry in state:
        if entry["kind"] == "adapter":
            write_file(tree / entry["path"], entry["backup"])
            changes.append("restored the fork's own %s" % entry["path"])
    backup_dir = tree / BACKUP_DIR
    for entry in state:
        if entry["backup"] is not None:
            (backup_dir / entry["path"]).unlink()
    if backup_dir.is_dir():
        for folder in (backup_dir / "include", backup_dir / "src", backup_dir):
            if folder.is_dir() and not any(folder.iterdir()):
                folder.rmdir()
        if backup_dir.exists():
            print("%s: %s/ holds files this script did not write; left in place" % (tree, BACKUP_DIR))
        else:
            changes.append("removed %s/" % BACKUP_DIR)

    report(tree, changes, "uninstalled affine_orb's adapter; rebuild the fork",
           "affine_orb's adapter is not installed; nothing changed")


def main(argv):
    if not argv or argv[0] not in FORKS:
        sys.exit("usage: install_adapter.py {%s} [options] FORK_DIR (run adapters/<fork>/install.sh)"
                 % ",".join(sorted(FORKS)))
    fork, name = argv[0], FORKS[argv[0]]["name"]
    parser = argparse.ArgumentParser(
        prog=script_name(fork),
        description="Installs affine_orb's %s adapter into an %s checkout: include/ORBextractor.h and "
                    "src/ORBextractor.cc become adapters/%s/ORBextractor.{h,cc} (the fork's own are kept in "
                    "%s/), and CMakeLists.txt gets marked lines adding affine_orb's include directories "
                    "and compiling src/ORBextractor.cc as C++17. Running it again changes nothing, or "
                    "refreshes the files after affine_orb changed; --uninstall restores the fork byte for "
                    "byte. It refuses a tree that is not an %s checkout or holds another extractor."
                    % (name, name, fork, BACKUP_DIR, name),
        epilog="Then rebuild the fork as usual (its build/ re-runs CMake by itself).")
    parser.add_argument("fork_dir", metavar="FORK_DIR", type=Path, help="the %s checkout" % name)
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--uninstall", action="store_true",
                      help="restore the fork's own extractor files and remove the CMake lines (and the "
                           "recovery lines)")
    mode.add_argument("--recovery", action="store_true",
                      help="also add ORBextractor::SetRecovering(%s); at the top of Tracking::GrabImageStereo, "
                           "GrabImageRGBD and GrabImageMonocular in %s (marked, one line each): the adapter's "
                           "recovery mode while tracking is lost" % (FORKS[fork]["lost"], TRACKING))
    mode.add_argument("--no-recovery", action="store_true", help="remove those lines again")
    parser.add_argument("--ignore-build-dir", action="store_true",
                        help="go ahead although FORK_DIR/%s names another source tree (by default that "
                             "is refused: rebuilding in that build/ would rebuild the other tree)" % BUILD_CACHE)
    parser.add_argument("--affine-orb", metavar="DIR", type=Path, default=PROJECT,
                        help="the affine_orb checkout whose adapter files are copied and whose include/ and "
                             "adapters/common/ the fork compiles against (default: %(default)s, the "
                             "checkout this script is in)")
    args = parser.parse_args(argv[1:])
    tree = args.fork_dir.resolve()
    try:
        if args.uninstall:
            uninstall(tree, fork, ignore_build_dir=args.ignore_build_dir)
        else:
            install(tree, fork, args.affine_orb.resolve(),
                    recovery=True if args.recovery else (False if args.no_recovery else None),
                    ignore_build_dir=args.ignore_build_dir)
    except Refusal as refusal:
        print("%s: error: %s" % (script_name(fork), refusal), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main(sys.argv[1:])
