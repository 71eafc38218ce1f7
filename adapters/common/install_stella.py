#!/usr/bin/env python3
"""Installs affine_orb's orb_extractor adapter into a stella_vslam checkout, or removes it.

adapters/stella_vslam/install.sh runs this file; `--help` explains the rest. Python 3.6 or later,
standard library only; the file helpers are install_adapter.py's (the ORB-SLAM installer).

What an install does to the checkout (STELLA below), and what --uninstall undoes byte for byte:
- stella's own src/stella_vslam/feature/orb_extractor.cc is saved in STELLA/.affine_orb_backup/ and
  replaced by adapters/stella_vslam/orb_extractor.cc; stella's orb_extractor.h stays;
- src/stella_vslam/feature/CMakeLists.txt gets, at its end, a block between two marker comments
  giving orb_extractor.cc alone, in the library target that file adds its sources to, the affine_orb
  checkout's include/ and adapters/common/ and -std=gnu++17 (set_source_files_properties with
  TARGET_DIRECTORY, CMake 3.18 or later). stella sets CMAKE_CXX_STANDARD 11 and compiles as the
  highest standard its dependencies ask for: C++14 with g2o 20230223 (the g2o of stella's
  Dockerfiles), too old for the adapter. Stella's other files keep their compile lines.

Recognition (the files are read, nothing is built): orb_extractor.h declares stella's
`class orb_extractor` with its public image_pyramid_; orb_extractor.cc is stella's own when it
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
STOCK_IDENTIFIER = re.compile(rb"\borb_extractor::distribute_keypoints\b")
HEADER_CLASS = re.compile(rb"\bclass[ \t]+orb_extractor\s*\{.*\bstd::vector<cv::Mat>[ \t]+image_pyramid_;", re.DOTALL)
TARGET_SOURCES = re.compile(rb"target_sources\s*\(\s*(\$\{PROJECT_NAME\}|[\w.-]+)[^)]*orb_extractor\.cc", re.DOTALL)


def classify(data):
    """'adapter' (affine_orb's), 'stock' (stella's own) or 'other', from a file's bytes."""
    return install_adapter.classify(data, STOCK_IDENTIFIER)


def check_tree(tree):
    """Refuses a tree that is not a stella_vslam checkout with the files the install changes; returns
    the target that feature/CMakeLists.txt adds orb_extractor.cc to."""
    for relative in (SOURCE, HEADER, CMAKE):
        if not (tree / relative).is_file():
            raise Refusal("%s is not a stella_vslam checkout: %s is missing" % (tree, relative))
    if not HEADER_CLASS.search((tree / HEADER).read_bytes()):
        raise Refusal("%s does not declare stella_vslam's orb_extractor with image_pyramid_" % (tree / HEADER))
    target = TARGET_SOURCES.search((tree / CMAKE).read_bytes())
    if not target:
        raise Refusal("%s does not add orb_extractor.cc with target_sources(): an unknown stella_vslam layout"
                      % (tree / CMAKE))
    return target.group(1).decode()


def strip_block(text):
    """`text` without this script's marked block (and the newline before it that the install added)."""
    begin = text.find("\n" + BEGIN_MARKER)
    if begin < 0:
        return text
    end = text.index(END_MARKER, begin) + len(END_MARKER)
    return text[:begin] + text[end + 1:] if text[end:end + 1] == "\n" else text[:begin] + text[end:]


def block(target, project):
    return ("\n%s\nset_source_files_properties(${CMAKE_CURRENT_SOURCE_DIR}/orb_extractor.cc TARGET_DIRECTORY %s\n"
            "  PROPERTIES INCLUDE_DIRECTORIES \"%s;%s\" COMPILE_OPTIONS -std=gnu++17)\n%s\n"
            % (BEGIN_MARKER, target, project / "include", project / "adapters" / "common", END_MARKER))


def install(tree, project):
    adapter = project / "adapters/stella_vslam/orb_extractor.cc"
    if not adapter.is_file() or not (project / "include/affine_orb").is_dir():
        raise Refusal("%s is not an affine_orb checkout with the stella_vslam adapter" % project)
    target = check_tree(tree)
    current = (tree / SOURCE).read_bytes()
    kind = classify(current)
    backup = tree / BACKUP_DIR / SOURCE
    if kind == "other":
        raise Refusal("%s is neither stella's own extractor nor affine_orb's adapter; nothing changed" % SOURCE)
    if kind == "adapter" and not backup.is_file():
        raise Refusal("%s is affine_orb's adapter but %s has no backup of stella's own" % (SOURCE, BACKUP_DIR))
    cmake = (tree / CMAKE).read_bytes().decode("utf-8", "surrogateescape")
    new_cmake = strip_block(cmake).rstrip("\n") + "\n" + block(target, project)
    changes = []
    if kind == "stock":
        write_file(backup, current, tree / SOURCE)
        changes.append("saved stella's %s in %s/" % (SOURCE, BACKUP_DIR))
    if current != adapter.read_bytes():
        write_file(tree / SOURCE, adapter.read_bytes(), tree / SOURCE)
        changes.append("%s: affine_orb's adapter" % SOURCE)
    if new_cmake != cmake:
        if kind == "stock":
            write_file(tree / BACKUP_DIR / CMAKE, cmake.encode("utf-8", "surrogateescape"), tree / CMAKE)
        write_file(tree / CMAKE, new_cmake.encode("utf-8", "surrogateescape"), tree / CMAKE)
        changes.append("%s: affine_orb's include directories" % CMAKE)
    print("\n".join(changes) if changes else "nothing to do: the adapter of %s is installed" % project)


def uninstall(tree):
    check_tree(tree)
    backups = [tree / BACKUP_DIR / relative for relative in (SOURCE, CMAKE)]
    if classify((tree / SOURCE).read_bytes()) != "adapter":
        print("nothing to do: %s is not affine_orb's adapter" % SOURCE)
        return
    if not all(b.is_file() for b in backups):
        raise Refusal("%s/ lacks stella's own files; nothing changed" % BACKUP_DIR)
    for relative, saved in zip((SOURCE, CMAKE), backups):
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
                    "(stella's own kept in %s/) and %s gets marked lines adding affine_orb's include "
                    "directories. Running it again changes nothing or refreshes the file; --uninstall restores "
                    "stella byte for byte. It refuses a tree that is not a stella_vslam checkout or holds "
                    "another extractor." % (SOURCE, BACKUP_DIR, CMAKE),
        epilog="Then rebuild stella_vslam as usual.")
    parser.add_argument("stella_dir", metavar="STELLA_DIR", type=Path, help="the stella_vslam checkout")
    parser.add_argument("--uninstall", action="store_true", help="restore stella's own files")
    parser.add_argument("--affine-orb", metavar="DIR", type=Path, default=PROJECT,
                        help="the affine_orb checkout (default: %(default)s, the one this script is in)")
    args = parser.parse_args(argv)
    tree = args.stella_dir.resolve()
    try:
        if args.uninstall:
            uninstall(tree)
        else:
            install(tree, args.affine_orb.resolve())
    except Refusal as refusal:
        print("%s: error: %s" % (SCRIPT, refusal), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main(sys.argv[1:])
