#!/usr/bin/python3
"""Names written in the documentation exist:

  - every header path (`ebslam/slam/dedvs_sensors.h`, `ebslam_ros/src/event_input.h`,
    `pose_filter_nodelet_base.h`), message or service name (`ebslam_msgs/ResetPose`, `Bump.msg`,
    `sensor_msgs/Image`) and nodelet type (`ebslam_ros/EventSlam3d`) written in the Markdown
    files, in the `doc` of launch-file arguments and in the comments of yaml files;
  - every message and service of a workspace package is named in the package tables (the rows
    for that package in README.md and docs/building.md).

A header path resolves when it is the end of a file path of the repository (after a `/`), a header
the build generates (<pkg>/<Msg>.h of a .msg or .srv, <pkg>/<Name>Config.h of a cfg/<Name>.cfg),
or a system header under /usr/include or /opt/ros/*/include. A message or service of a workspace
package must be its msg/<Name>.msg or srv/<Name>.srv; one of another package is checked against
its installed definition (/usr/share/<pkg>/{msg,srv}) where that package is installed.

Usage: docs_references_test.py [JUNIT_XML]   (exit 1 on a failure)
"""
import glob
import os
import re
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ET

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# Folders that hold no documentation of this repository (build output, fuzz corpora).
SKIPPED_DIRS = {".git", ".ws", "build", "devel", "install", "corpus", "node_modules"}

HEADER = re.compile(r"(?<![\w/.:-])((?:[A-Za-z0-9_.-]+/)*[A-Za-z0-9_-]+\.(?:h|hpp))(?![\w])")
TYPE_NAME = re.compile(r"(?<![\w/.-])([a-z][a-z0-9_]*)/([A-Z][A-Za-z0-9]*)(?![\w/.])")
DEFINITION_FILE = re.compile(r"(?<![\w/.-])([A-Z][A-Za-z0-9]*)\.(msg|srv)\b")
SYSTEM_INCLUDE_ROOTS = ["/usr/include"] + sorted(glob.glob("/usr/include/*/")) + \
    sorted(glob.glob("/opt/ros/*/include"))


def repository_files(root):
    """Relative paths of the repository's files (git's view when it is a git tree)."""
    try:
        out = subprocess.run(["git", "-C", root, "ls-files", "--cached", "--others",
                              "--exclude-standard"], capture_output=True, text=True, check=True)
        files = [f for f in out.stdout.splitlines() if f]
        if files:
            return [f for f in files if not set(f.split("/")[:-1]) & SKIPPED_DIRS]
    except (OSError, subprocess.CalledProcessError):
        pass
    files = []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = [d for d in dirnames if d not in SKIPPED_DIRS]
        for name in filenames:
            files.append(os.path.relpath(os.path.join(dirpath, name), root))
    return files


class Tree:
    """What exists: files, packages and their messages, services and dynamic_reconfigure cfgs."""

    def __init__(self, root):
        self.root = root
        self.files = repository_files(root)
        self.basenames = {os.path.basename(f) for f in self.files}
        self.packages = {}  # name -> folder (relative)
        for f in self.files:
            if os.path.basename(f) == "package.xml":
                with open(os.path.join(root, f), encoding="utf-8") as xml:
                    m = re.search(r"<name>\s*([^<\s]+)\s*</name>", xml.read())
                if m:
                    self.packages[m.group(1)] = os.path.dirname(f)
        self.nodelets = {}  # package -> nodelet type names of its nodelet_plugins.xml
        for package, folder in self.packages.items():
            plugins = os.path.join(root, folder, "nodelet_plugins.xml")
            if os.path.isfile(plugins):
                with open(plugins, encoding="utf-8") as xml:
                    self.nodelets[package] = set(re.findall(r'<class name="([^"]+)"', xml.read()))
        self.definitions = {}  # package -> {Name: "msg" | "srv"}
        self.generated_headers = set()
        for f in self.files:
            parts = f.split("/")
            folder = "/".join(parts[:-2])
            package = next((p for p, d in self.packages.items() if d == folder), None)
            if package is None:
                continue
            stem, ext = os.path.splitext(parts[-1])
            if parts[-2] in ("msg", "srv") and ext == "." + parts[-2]:
                self.definitions.setdefault(package, {})[stem] = parts[-2]
                self.generated_headers.add(f"{package}/{stem}.h")
                if ext == ".srv":
                    self.generated_headers.update(
                        {f"{package}/{stem}Request.h", f"{package}/{stem}Response.h"})
            elif parts[-2] == "cfg" and ext == ".cfg":
                self.generated_headers.add(f"{package}/{stem}Config.h")

    def header_exists(self, ref):
        if ref in self.generated_headers:
            return True
        if "/" not in ref:
            if ref in self.basenames:
                return True
        elif any(f == ref or f.endswith("/" + ref) for f in self.files):
            return True
        return any(os.path.isfile(os.path.join(r, ref)) for r in SYSTEM_INCLUDE_ROOTS)

    def type_problem(self, package, name):
        """Why package/name is no message or service; None when it is (or cannot be checked)."""
        if package in self.definitions:
            if name in self.definitions[package]:
                return None
            return f"{package} has no msg/{name}.msg or srv/{name}.srv"
        if package in self.packages:
            # A nodelet type (ebslam_ros/EventSlam3d) of a package that has nodelets.
            if package in self.nodelets and f"{package}/{name}" not in self.nodelets[package]:
                return f"{package} has no message, service or nodelet {name}"
            return None
        installed = f"/usr/share/{package}"
        if (package.endswith("_msgs") or package.endswith("_srvs")) and os.path.isdir(installed):
            for kind in ("msg", "srv"):
                if os.path.isfile(os.path.join(installed, kind, f"{name}.{kind}")):
                    return None
            return f"the installed {package} has no {name}.msg or {name}.srv"
        return None

    def definition_file_exists(self, name, kind):
        return any(name in defs and defs[name] == kind for defs in self.definitions.values())


def documentation_texts(root, files):
    """(where, text) of every Markdown file, launch-argument doc and yaml comment line."""
    texts = []
    for f in files:
        path = os.path.join(root, f)
        if f.endswith(".md"):
            with open(path, encoding="utf-8", errors="replace") as md:
                for number, line in enumerate(md, 1):
                    texts.append((f"{f}:{number}", line))
        elif f.endswith(".launch") or (f.endswith(".xml") and "/launch/" in "/" + f):
            try:
                tree = ET.parse(path)
            except ET.ParseError:
                continue
            for arg in tree.iter("arg"):
                if arg.get("doc"):
                    texts.append((f"{f}: arg {arg.get('name')}", arg.get("doc")))
        elif f.endswith((".yaml", ".yml")):
            with open(path, encoding="utf-8", errors="replace") as yaml:
                for number, line in enumerate(yaml, 1):
                    if "#" in line and not line.lstrip().startswith("%"):
                        texts.append((f"{f}:{number}", line[line.index("#"):]))
    return texts


def without_urls(text):
    return re.sub(r"\b(?:https?|ftp|file)://\S+", " ", text)


def reference_problems(tree, texts):
    problems = []
    for where, text in texts:
        text = without_urls(text)
        for m in HEADER.finditer(text):
            if not tree.header_exists(m.group(1)):
                problems.append(f"{where}: header {m.group(1)} does not exist")
        for m in TYPE_NAME.finditer(text):
            problem = tree.type_problem(m.group(1), m.group(2))
            if problem:
                problems.append(f"{where}: {m.group(1)}/{m.group(2)}: {problem}")
        for m in DEFINITION_FILE.finditer(text):
            if not tree.definition_file_exists(m.group(1), m.group(2)):
                problems.append(f"{where}: {m.group(0)} is no message or service of the workspace")
    return problems


def table_problems(tree, table_files=("README.md", "docs/building.md")):
    """Messages and services missing from their package's row of the package tables."""
    problems = []
    for f in table_files:
        path = os.path.join(tree.root, f)
        if not os.path.isfile(path):
            continue
        with open(path, encoding="utf-8") as md:
            rows = [line for line in md if line.startswith("|")]
        for package, definitions in sorted(tree.definitions.items()):
            row = next((r for r in rows if re.match(r"\|\s*`%s/?`\s*\|" % re.escape(package), r)),
                       None)
            if row is None:
                problems.append(f"{f}: no table row for the package {package}")
                continue
            for name in sorted(definitions):
                if not re.search(r"(?<![\w])%s(?![\w])" % re.escape(name), row):
                    problems.append(f"{f}: the row of {package} does not name {name} "
                                    f"({definitions[name]}/{name}.{definitions[name]})")
    return problems


def check(root):
    tree = Tree(root)
    return reference_problems(tree, documentation_texts(root, tree.files)) + table_problems(tree)


class DocsReferencesTest(unittest.TestCase):
    def test_tree_names_only_what_exists(self):
        problems = check(REPO)
        self.assertEqual(problems, [], "\n" + "\n".join(problems))

    def problems_of(self, files):
        """The check on a copy of the repository's packages with `files` {path: text} added."""
        with tempfile.TemporaryDirectory() as tmp:
            tree = Tree(REPO)
            for path, text in files.items():
                full = os.path.join(tmp, path)
                os.makedirs(os.path.dirname(full), exist_ok=True)
                with open(full, "w", encoding="utf-8") as out:
                    out.write(text)
            return reference_problems(tree, documentation_texts(tmp, list(files)))

    def test_a_header_at_a_wrong_place_fails(self):
        wrong = "Format: `ebslam/simulation/dedvs_sensors.h`.\n"
        problems = self.problems_of({"docs/wrong.md": wrong})
        self.assertEqual(len(problems), 1, problems)
        self.assertIn("ebslam/simulation/dedvs_sensors.h", problems[0])
        right = "Format: `ebslam/slam/dedvs_sensors.h`.\n"
        self.assertEqual(self.problems_of({"docs/right.md": right}), [])

    def test_a_wrong_name_in_a_launch_doc_and_a_yaml_comment_fails(self):
        launch = ('<launch>\n  <arg name="calibration" default="x" '
                  'doc="format in ebslam/slam/dedvs_sensor.h, service ebslam_msgs/ResetPoses"/>\n'
                  '</launch>\n')
        problems = self.problems_of({"launch/wrong.launch": launch,
                                     "config/wrong.yaml": "# messages: Bumps.msg\nkey: 1\n"})
        self.assertEqual(len(problems), 3, problems)
        joined = "\n".join(problems)
        for name in ("dedvs_sensor.h", "ebslam_msgs/ResetPoses", "Bumps.msg"):
            self.assertIn(name, joined)
        self.assertEqual(len(self.problems_of({"docs/n.md": "`ebslam_ros/EventSlam4d`\n"})), 1)

    def test_an_unlisted_message_fails(self):
        tree = Tree(REPO)
        tree.definitions = {p: dict(d) for p, d in tree.definitions.items()}
        tree.definitions.setdefault("ebslam_msgs", {})["NotInTheTables"] = "msg"
        problems = table_problems(tree)
        self.assertEqual(len(problems), 2, problems)
        self.assertTrue(all("NotInTheTables" in p for p in problems), problems)


def main():
    suite = unittest.defaultTestLoader.loadTestsFromTestCase(DocsReferencesTest)
    tests = list(suite)
    result = unittest.TextTestRunner(verbosity=2).run(suite)
    if len(sys.argv) > 1:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from workspace_checks import write_junit  # noqa: E402
        write_junit(result, tests, sys.argv[1], "docs_references")
    return 0 if result.wasSuccessful() else 1


if __name__ == "__main__":
    sys.exit(main())
