#!/usr/bin/env python3
"""Installs affine_orb's orb_extractor adapter into a stella_vslam checkout, or removes it.

adapters/stella_vslam/install.sh runs this file; `--help` explains the rest. Python 3.6 or later,
standard library only; the file helpers are install_adapter.py's (the ORB-SLAM installer).

What an install does to the checkout (STELLA below), and what --uninstall undoes byte for byte
(each changed file's original is saved in STELLA/.affine_orb_backup/ first):
- src/stella_vslam/feature/orb_extractor.cc is replaced by adapters/stella_vslam/orb_extractor.cc;
- src/stella_vslam/feature/orb_extractor.h gets, after image_pyramid_, marked public declarations
  of configure_affine_orb(), which reads affine_orb's options from the YAML `Feature: affine_orb:`
  map, and set_affine_orb_recovering(); src/stella_vslam/system.cc a marked line after each
  construction of an orb_extractor calling the first with the config's `Feature` node (stella
  hands its extractor orb_params and `Preprocessing` values only) and, with --recovery, marked
  lines after each frame's tracking telling the extractors whether tracking is lost;
- src/stella_vslam/feature/CMakeLists.txt gets, at its end, a block between two marker comments
  giving orb_extractor.cc alone, in the library target that file adds its sources to, the affine_orb
  checkout's include/ and adapters/common/ and -std=gnu++17 (set_source_files_properties with
  TARGET_DIRECTORY, CMake 3.18 or later). stella sets CMAKE_CXX_STANDARD 11 and compiles as the
  highest standard its dependencies ask for: C++14 with g2o 20230223 (the g2o of stella's
  Dockerfiles), too old for the adapter. Stella's other files keep their compile lines.

Recognition (the files are read, nothing is built): orb_extractor.h declares stella's
`class orb_extractor` with its public image_pyramid_; system.cc constructs extractor_left_ with
`new feature::orb_extractor(...)` and tracks a frame in one `const auto cam_pose_wc =
tracker_->feed_frame(frm);`; orb_extractor.cc is stella's own when it
defines orb_extractor::distribute_keypoints, the adapter's when it includes "affine_orb_adapter/";
another file there is another extractor, and the script leaves such a tree alone.
"""
import argparse
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import install_adapter  # noqa: E402
from install_adapter import BACKUP_DIR, BEGIN_MARKER, END_MARKER, PROJECT, Refusal, write_file  # noqa: E402

SCRIPT = "adapters/stella_vslam/install.sh"
FEATURE = "src/stella_vslam/feature"
SOURCE = FEATURE + "/orb_extractor.cc"
HEADER = FEATURE + "/orb_extractor.h"
CMAKE = FEATURE + "/CMakeLists.txt"
SYSTEM = "src/stella_vslam/system.cc"
STOCK_IDENTIFIER = re.compile(rb"\borb_extractor::distribute_keypoints\b")
HEADER_CLASS = re.compile(rb"\bclass[ \t]+orb_extractor\s*\{.*\bstd::vector<cv::Mat>[ \t]+image_pyramid_;", re.DOTALL)
TARGET_SOURCES = re.compile(rb"target_sources\s*\(\s*(\$\{PROJECT_NAME\}|[\w.-]+)[^)]*orb_extractor\.cc", re.DOTALL)
CONSTRUCTION = re.compile(rb"^([ \t]*)(extractor_(?:left|right)_)[ \t]*=[ \t]*new[ \t]+feature::orb_extractor\([^;]*\);[ \t]*$",
                          re.MULTILINE)
TRACKED = re.compile(rb"^([ \t]*)const auto cam_pose_wc = tracker_->feed_frame\(frm\);[ \t]*$", re.MULTILINE)
DECLARATION = ("\n    // affine_orb adapter (%s): the options of YAML `Feature: affine_orb:`, and"
               "\n    // whether tracking is lost (the recovery options then serve, with --recovery)"
               "\n    void configure_affine_orb(const YAML::Node& feature, bool recovery_hook);"
               "\n    void set_affine_orb_recovering(bool recovering);" % SCRIPT).encode()
CALL = (rb'\n\1\2->configure_affine_orb(util::yaml_optional_ref(cfg->yaml_node_, "Feature"), %s);'
        rb'  // affine_orb adapter')
RECOVERY_MARKER = b"// affine_orb recovery mode (install.sh --recovery)"
RECOVERY = (rb"\n\1for (auto* extractor : {extractor_left_, extractor_right_}) {"
            rb"\n\1    if (extractor) extractor->set_affine_orb_recovering(tracker_->tracking_state_ == tracker_state_t::Lost);"
            rb"\n\1}  " + RECOVERY_MARKER)


def classify(data):
    """'adapter' (affine_orb's), 'stock' (stella's own) or 'other', from a file's bytes."""
    return install_adapter.classify(data, STOCK_IDENTIFIER)


def check_tree(tree):
    """Refuses a tree that is not a stella_vslam checkout with the files the install changes; returns
    the target that feature/CMakeLists.txt adds orb_extractor.cc to."""
    for relative in (SOURCE, HEADER, CMAKE, SYSTEM):
        if not (tree / relative).is_file():
            raise Refusal("%s is not a stella_vslam checkout: %s is missing" % (tree, relative))
    if not HEADER_CLASS.search(original(tree, HEADER)):
        raise Refusal("%s does not declare stella_vslam's orb_extractor with image_pyramid_" % (tree / HEADER))
    system = original(tree, SYSTEM)
    if b"extractor_left_" not in b" ".join(m.group(2) for m in CONSTRUCTION.finditer(system)):
        raise Refusal("%s does not construct extractor_left_ with new feature::orb_extractor(...): an unknown "
                      "stella_vslam layout" % (tree / SYSTEM))
    if len(TRACKED.findall(system)) != 1:
        raise Refusal("%s has no single `const auto cam_pose_wc = tracker_->feed_frame(frm);` for the recovery "
                      "switch: an unknown stella_vslam layout" % (tree / SYSTEM))
    target = TARGET_SOURCES.search(original(tree, CMAKE))
    if not target:
        raise Refusal("%s does not add orb_extractor.cc with target_sources(): an unknown stella_vslam layout"
                      % (tree / CMAKE))
    return target.group(1).decode()


def original(tree, relative):
    """stella's own bytes of `relative`: its backup once the install has changed it."""
    backup = tree / BACKUP_DIR / relative
    return (backup if backup.is_file() else tree / relative).read_bytes()


def patched_header(data):
    """stella's orb_extractor.h with the adapter's declaration after image_pyramid_ (the test of the
    adapter compiles against this too)."""
    end = HEADER_CLASS.search(data).end()
    return data[:end] + DECLARATION + data[end:]


def patched_system(data, recovery):
    """stella's system.cc with the configure_affine_orb() calls and, with `recovery`, the switch after
    each frame's tracking."""
    call = CALL % (b"true" if recovery else b"false")
    data = CONSTRUCTION.sub(lambda m: m.group(0) + m.expand(call), data)
    return TRACKED.sub(lambda m: m.group(0) + m.expand(RECOVERY), data) if recovery else data


def cmake_block(target, project):
    return ("\n%s\nset_source_files_properties(${CMAKE_CURRENT_SOURCE_DIR}/orb_extractor.cc TARGET_DIRECTORY %s\n"
            "  PROPERTIES INCLUDE_DIRECTORIES \"%s;%s\" COMPILE_OPTIONS -std=gnu++17)\n%s\n"
            % (BEGIN_MARKER, target, project / "include", project / "adapters" / "common", END_MARKER))


def install(tree, project, recovery=None):
    """recovery: True adds the recovery switch to system.cc, False removes it, None keeps it as it is."""
    adapter = project / "adapters/stella_vslam/orb_extractor.cc"
    if not adapter.is_file() or not (project / "include/affine_orb").is_dir():
        raise Refusal("%s is not an affine_orb checkout with the stella_vslam adapter" % project)
    target = check_tree(tree)
    kind = classify((tree / SOURCE).read_bytes())
    if kind == "other":
        raise Refusal("%s is neither stella's own extractor nor affine_orb's adapter; nothing changed" % SOURCE)
    if kind == "adapter" and not (tree / BACKUP_DIR / SOURCE).is_file():
        raise Refusal("%s is affine_orb's adapter but %s has no backup of stella's own" % (SOURCE, BACKUP_DIR))
    if recovery is None:
        recovery = RECOVERY_MARKER in (tree / SYSTEM).read_bytes()
    cmake = original(tree, CMAKE)
    wanted = {SOURCE: adapter.read_bytes(), HEADER: patched_header(original(tree, HEADER)),
              SYSTEM: patched_system(original(tree, SYSTEM), recovery),
              CMAKE: cmake.rstrip(b"\n") + b"\n" + cmake_block(target, project).encode()}
    what = {SOURCE: "affine_orb's adapter", HEADER: "declares configure_affine_orb(), set_affine_orb_recovering()",
            SYSTEM: "calls configure_affine_orb()" + (", reports lost tracking (recovery mode)" if recovery else ""),
            CMAKE: "affine_orb's include directories"}
    changes = []
    for relative, data in wanted.items():
        current = (tree / relative).read_bytes()
        if current == data:
            continue
        backup = tree / BACKUP_DIR / relative
        if not backup.is_file():
            write_file(backup, current, tree / relative)
            changes.append("saved stella's %s in %s/" % (relative, BACKUP_DIR))
        write_file(tree / relative, data, tree / relative)
        changes.append("%s: %s" % (relative, what[relative]))
    print("\n".join(changes) if changes else "nothing to do: the adapter of %s is installed" % project)


def uninstall(tree):
    check_tree(tree)
    if classify((tree / SOURCE).read_bytes()) != "adapter":
        print("nothing to do: %s is not affine_orb's adapter" % SOURCE)
        return
    if not (tree / BACKUP_DIR / SOURCE).is_file():
        raise Refusal("%s/ lacks stella's own %s; nothing changed" % (BACKUP_DIR, SOURCE))
    for relative in (SOURCE, HEADER, SYSTEM, CMAKE):
        saved = tree / BACKUP_DIR / relative
        if saved.is_file():
            write_file(tree / relative, saved.read_bytes(), saved)
            saved.unlink()
            print("%s: stella's own, restored" % relative)
    for folder in sorted((tree / BACKUP_DIR).rglob("*"), reverse=True) + [tree / BACKUP_DIR]:
        if folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()


def main(argv):
    parser = argparse.ArgumentParser(
        prog=SCRIPT,
        description="Installs affine_orb's stella_vslam adapter: %s becomes adapters/stella_vslam/orb_extractor.cc "
                    "(stella's own kept in %s/), %s gets marked lines adding affine_orb's include "
                    "directories and orb_extractor.h and system.cc a marked line each reading the YAML "
                    "`Feature: affine_orb:` options. Running it again changes nothing or refreshes the file; --uninstall restores "
                    "stella byte for byte. It refuses a tree that is not a stella_vslam checkout or holds "
                    "another extractor." % (SOURCE, BACKUP_DIR, CMAKE),
        epilog="Then rebuild stella_vslam as usual.")
    parser.add_argument("stella_dir", metavar="STELLA_DIR", type=Path, help="the stella_vslam checkout")
    parser.add_argument("--uninstall", action="store_true", help="restore stella's own files")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--recovery", dest="recovery", action="store_const", const=True,
                      help="also report lost tracking to the extractor: the recovery options (YAML "
                           "recovery_* keys) then serve those frames")
    mode.add_argument("--no-recovery", dest="recovery", action="store_const", const=False,
                      help="remove that report (a plain install keeps what is there)")
    parser.add_argument("--affine-orb", metavar="DIR", type=Path, default=PROJECT,
                        help="the affine_orb checkout (default: %(default)s, the one this script is in)")
    args = parser.parse_args(argv)
    tree = args.stella_dir.resolve()
    try:
        if args.uninstall:
            uninstall(tree)
        else:
            install(tree, args.affine_orb.resolve(), args.recovery)
    except Refusal as refusal:
        print("%s: error: %s" % (SCRIPT, refusal), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main(sys.argv[1:])
