#!/usr/bin/env python3
"""check_links.py -- every link and document reference of the project resolves.

usage: check_links.py [ROOT]        check the tree at ROOT (default: this file's project)
       check_links.py --self-test   build a scratch tree with good and broken links and check
                                    that exactly the broken ones are reported

What is checked (Python 3 standard library only):
- In every tracked *.md file (git ls-files; every *.md under ROOT outside a git checkout), every
  inline link, image and reference definition whose target is relative: the file or folder must
  exist, and an #anchor must match a heading of the target Markdown file (or of the same file for
  a bare #anchor) by GitHub's slug rules.
- In every tracked text file under include/, adapters/, bench/, examples/ and tests/, and in the
  prose of every *.md file: each reference to a Markdown file of the project written as a path
  (docs/slam.md, adapters/README.md, README.md, ...), with an optional #anchor, and the section a
  reference names in quotes right after it (docs/slam.md, "Shortfalls"; README, "Layout"). The path
  is read from ROOT, then from the referring file's folder; the quoted name must begin a heading of
  that file (Markdown emphasis and code marks ignored, case-insensitive). Not checked: paths that
  leave the project (../shared/...) or do not start in it (DIR/out.md), and a file name without a
  folder that names no file of ROOT or of the referring file's folder (an output such as
  eval_two_view.md).

Exit status 0 when everything resolves, 1 with one line per broken link, FILE:LINE: what.
"""
import os
import re
import subprocess
import sys
import tempfile
import unicodedata

kCodeRoots = ("include/", "adapters/", "bench/", "examples/", "tests/")
kSelf = os.path.abspath(__file__)

# [text](target "title") and ![alt](target); the target may be wrapped in <>.
kInlineLink = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*(<[^>]*>|[^\s()]*(?:\([^\s()]*\)[^\s()]*)*)"
                         r"(?:\s+(?:\"[^\"]*\"|'[^']*'|\([^)]*\)))?\s*\)")
kReferenceDefinition = re.compile(r"^ {0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)", re.M)
kFence = re.compile(r"^ {0,3}(`{3,}|~{3,})")
kAtxHeading = re.compile(r"^ {0,3}(#{1,6})(?:[ \t]+(.*?))?(?:[ \t]+#+)?[ \t]*$")
kSetextUnderline = re.compile(r"^ {0,3}(=+|-+)[ \t]*$")
kHtmlAnchor = re.compile(r"<a\s+[^>]*?(?:name|id)\s*=\s*[\"']([^\"']+)[\"']", re.I)
# A reference to a project Markdown file: a path ending in .md (not inside a longer path or a URL),
# or the bare word README followed by a quoted section; an optional #anchor; an optional quoted
# section name after an optional comma (the quote may continue on the next comment line).
kContinuation = r"(?:\n[ \t]*(?:///|//|#|\*|--)?[ \t]*)"
kReference = re.compile(
    r"(?<![\w./:#-])(?P<path>(?:\.\./)*(?:[\w.-]+/)*[\w.-]+\.md|README(?=,?[ \t]*\"))"
    r"(?P<anchor>#[\w-]+)?`?"
    r"(?:,?(?:[ \t]|" + kContinuation + r")*\"(?P<section>(?:[^\"\n]|" + kContinuation + r"){1,120}?)\")?")


def is_external(target):
    return bool(re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target)) or target.startswith("//")


def strip_markup(text):
    """The text GitHub renders for a heading: links become their text, code and emphasis marks go."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)
    text = re.sub(r"<[^>]+>", "", text)
    text = text.replace("`", "")
    text = re.sub(r"(\*+|(?<!\w)_+|_+(?!\w))", "", text)
    return text.strip()


def github_slug(heading):
    """GitHub's anchor for a heading: lower case, every character but letters, digits, marks, '-',
    '_' and spaces removed, each space a '-' (github-slugger)."""
    out = []
    for ch in strip_markup(heading).lower():
        category = unicodedata.category(ch)
        if ch in " -_" or category[0] in "LNM":
            out.append("-" if ch == " " else ch)
    return "".join(out)


def prose_lines(text):
    """(line number, line) for every line outside fenced code blocks."""
    fence = None
    for number, line in enumerate(text.split("\n"), 1):
        m = kFence.match(line)
        if fence is None and m:
            fence = m.group(1)[0] * len(m.group(1))
            continue
        if fence is not None:
            if line.strip().startswith(fence) and set(line.strip()) <= set(fence[0]):
                fence = None
            continue
        yield number, line


def headings(text):
    """The headings of a Markdown text: their rendered text, in order."""
    found = []
    previous = None
    for _, line in prose_lines(text):
        m = kAtxHeading.match(line)
        if m:
            found.append(m.group(2) or "")
        elif previous is not None and previous.strip() and kSetextUnderline.match(line) \
                and not kAtxHeading.match(previous) and not previous.startswith(("    ", "\t")):
            found.append(previous.strip())
        previous = line
    return found


class Tree:
    def __init__(self, root):
        self.root = os.path.abspath(root)
        self.cache = {}
        self.files = self.tracked_files()

    def tracked_files(self):
        try:
            out = subprocess.run(["git", "-C", self.root, "ls-files", "-z"], check=True,
                                 stdout=subprocess.PIPE, stderr=subprocess.DEVNULL).stdout
            return sorted(f for f in out.decode("utf-8").split("\0") if f)
        except (OSError, subprocess.CalledProcessError):
            files = []
            for directory, subdirs, names in os.walk(self.root):
                subdirs[:] = [d for d in subdirs if not d.startswith(".") and d != "build"]
                for name in names:
                    files.append(os.path.relpath(os.path.join(directory, name), self.root).replace(os.sep, "/"))
            return sorted(files)

    def read(self, path):
        if path not in self.cache:
            try:
                with open(path, "rb") as f:
                    data = f.read()
                self.cache[path] = None if b"\0" in data else data.decode("utf-8", "replace")
            except OSError:
                self.cache[path] = None
        return self.cache[path]

    def anchors(self, path):
        text = self.read(path) or ""
        slugs, seen = set(), {}
        for heading in headings(text):
            slug = github_slug(heading)
            n = seen.get(slug, 0)
            seen[slug] = n + 1
            slugs.add(slug if n == 0 else "%s-%d" % (slug, n))
        slugs.update(kHtmlAnchor.findall(text))
        return slugs

    def section_names(self, path):
        return [re.sub(r"\s+", " ", strip_markup(h)).lower() for h in headings(self.read(path) or "")]


def check_markdown_links(tree, rel, text, problems):
    here = os.path.dirname(os.path.join(tree.root, rel))
    for number, line in prose_lines(text):
        line = re.sub(r"(`+)(?:(?!\1).)+\1", "", line)  # code spans hold no links
        targets = [m.group(1) for m in kInlineLink.finditer(line)]
        targets += [m.group(1) for m in kReferenceDefinition.finditer(line)]
        for target in targets:
            target = target.strip("<>")
            if not target or is_external(target):
                continue
            path, _, anchor = target.partition("#")
            resolved = os.path.normpath(os.path.join(here, path)) if path else os.path.join(tree.root, rel)
            where = "%s:%d" % (rel, number)
            if not os.path.exists(resolved):
                problems.append("%s: link to %s: no such file" % (where, target))
            elif anchor and resolved.endswith(".md") and anchor not in tree.anchors(resolved):
                problems.append("%s: link to %s: no heading with the anchor #%s in %s"
                                % (where, target, anchor, os.path.relpath(resolved, tree.root)))


def check_references(tree, rel, text, problems):
    here = os.path.dirname(os.path.join(tree.root, rel))
    for m in kReference.finditer(text):
        path = m.group("path")
        if path == "README":
            path = "README.md"
        if path.startswith("../"):
            continue  # outside the project
        where = "%s:%d" % (rel, text.count("\n", 0, m.start()) + 1)
        candidates = [os.path.normpath(os.path.join(tree.root, path)), os.path.normpath(os.path.join(here, path))]
        resolved = next((c for c in candidates if os.path.isfile(c)), None)
        first = path.split("/")[0]
        if resolved is None and ("/" not in path or not any(
                os.path.isdir(os.path.join(base, first)) for base in (tree.root, here))):
            continue  # a file name alone, or a path that does not start in the project (DIR/out.md)
        if resolved is None:
            problems.append("%s: reference to %s: no such file" % (where, path))
            continue
        anchor = m.group("anchor")
        if anchor and anchor[1:] not in tree.anchors(resolved):
            problems.append("%s: reference to %s%s: no heading with that anchor" % (where, path, anchor))
        section = m.group("section")
        if section:
            name = re.sub(kContinuation, " ", section)
            name = re.sub(r"\s+", " ", strip_markup(name)).lower()
            if not any(h.startswith(name) for h in tree.section_names(resolved)):
                problems.append('%s: reference to %s, "%s": no heading begins so' % (where, path, section.strip()))


def check(root):
    tree = Tree(root)
    problems = []
    for rel in tree.files:
        full = os.path.join(tree.root, rel)
        if os.path.abspath(full) == kSelf or not os.path.isfile(full):
            continue
        if rel.endswith(".md"):
            text = tree.read(full)
            if text is None:
                continue
            check_markdown_links(tree, rel, text, problems)
            check_references(tree, rel, "\n".join(_numbered_prose(text)), problems)
        elif rel.startswith(kCodeRoots):
            text = tree.read(full)
            if text is not None:
                check_references(tree, rel, text, problems)
    return problems


def _numbered_prose(text):
    """The lines of a Markdown text with fenced code and link targets blanked, line numbers kept."""
    keep = dict(prose_lines(text))
    for number, line in enumerate(text.split("\n"), 1):
        yield re.sub(r"\]\([^)]*\)", "]", keep[number]) if number in keep else ""


def self_test():
    with tempfile.TemporaryDirectory() as root:
        def write(rel, text):
            path = os.path.join(root, rel)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)
        write("README.md", "# Top\n\n## How it measures\n\n[good](docs/a.md#the-walk-step-1)\n"
                           "[bad anchor](docs/a.md#no-such-section)\n[bad file](docs/missing.md)\n"
                           "[self](#how-it-measures)\n```\n[in code](nowhere.md)\n```\n")
        write("docs/a.md", "# A\n\n## The walk: step 1\n\n## Shortfalls\n")
        write("include/x.hpp", "/// good (docs/a.md, \"Shortfalls\"); good docs/a.md#shortfalls\n"
                               "/// bad (docs/a.md, \"Gone\"); bad docs/b.md; bad README.md#nothing\n"
                               "/// good (README, \"How it\n/// measures\"); outside ../shared/x.md, DIR/out.md, out.md\n")
        problems = check(root)
        expected = ["README.md:6: link to docs/a.md#no-such-section",
                    "README.md:7: link to docs/missing.md",
                    'include/x.hpp:2: reference to docs/a.md, "Gone"',
                    "include/x.hpp:2: reference to docs/b.md",
                    "include/x.hpp:2: reference to README.md#nothing"]
        ok = len(problems) == len(expected) and all(
            any(p.startswith(e) for p in problems) for e in expected)
        assert github_slug("Shortfalls: a level short of corners keeps its shortfall") == \
            "shortfalls-a-level-short-of-corners-keeps-its-shortfall"
        assert github_slug("Monocular initialisation on `shake` (`init_chain.sh`)") == \
            "monocular-initialisation-on-shake-init_chainsh"
        assert github_slug("Seeds 1–10, ORB-SLAM3") == "seeds-110-orb-slam3"
        if not ok:
            print("self-test failed; reported:\n  " + "\n  ".join(problems) + "\nexpected:\n  " + "\n  ".join(expected))
            return 1
        print("self-test passed: %d broken links caught, the good ones accepted" % len(expected))
        return 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    if len(argv) > 2 or (len(argv) == 2 and argv[1].startswith("-")):
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    root = argv[1] if len(argv) == 2 else os.path.join(os.path.dirname(kSelf), "..")
    problems = check(root)
    for p in problems:
        print(p)
    sys.stdout.flush()
    if problems:
        print("%d broken link(s)" % len(problems), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
