#!/usr/bin/python3
"""Checks that every package.xml declares what its package's build finds and its Python imports.

For each package (a folder with a package.xml under the repository, not in .ws or a CATKIN_IGNOREd
folder) it reads
  - CMake: CMakeLists.txt, cmake/*.cmake, cmake/*.cmake.in and the files they include() by a path
    inside the repository: every find_package(<Name>) (and find_dependency), the COMPONENTS of
    find_package(catkin ...) (set() variables expanded) and every pkg_check_modules module;
  - Python: every *.py file and every file with a python shebang; top-level imported modules that are
    neither the standard library nor a module of the package itself.
Each name is mapped to a rosdep key by scripts/rosdep_debian.txt ("cmake"/"python" lines; a catkin
component or a ROS Python module is its own key) and must be declared in package.xml:
  - a find outside if(CATKIN_ENABLE_TESTING)/if(BUILD_TESTING) as <depend>, <build_depend>,
    <buildtool_depend> or <build_export_depend>;
  - a find inside such a block, or an import by a file under test/, by any dependency tag
    (<test_depend> is enough);
  - any other import as <depend> or <exec_depend>.
Every declared key must also have a "key" line (its Debian packages) unless it is a package of this
workspace, so that scripts/install_deps.sh can install it. QUIET finds (optional) and CMake's own
modules (Threads, PkgConfig, GoogleTest...) are not dependencies.

Usage: check_package_deps.py [--root DIR] [--map FILE] [--list-debian]
  --list-debian  print the Debian packages of every declared key (for install_deps.sh) and exit.
Exit status 0 when every package is complete, 1 on a gap (each printed as package: what, where).
"""
import argparse
import ast
import os
import re
import sys
import xml.etree.ElementTree as ET

BUILD_TAGS = {"depend", "build_depend", "buildtool_depend", "build_export_depend"}
EXEC_TAGS = {"depend", "exec_depend"}
ALL_TAGS = BUILD_TAGS | EXEC_TAGS | {"test_depend", "doc_depend"}
# CMake's own find modules and the build tool itself: nothing to install for them.
CMAKE_BUILTIN = {"Threads", "PkgConfig", "GoogleTest", "CTest", "GNUInstallDirs",
                 "CMakePackageConfigHelpers", "MPI"}
SKIP_DIRS = {".ws", ".git", "build", "devel", "install", "__pycache__"}


def load_map(path):
    keys, cmake, python = {}, {}, {}
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.split("#", 1)[0].split()
            if not line:
                continue
            kind, name, *rest = line
            if kind == "key" and rest:
                keys[name] = rest
            elif kind == "cmake" and len(rest) == 1:
                cmake[name] = rest[0]
            elif kind == "python" and len(rest) == 1:
                python[name] = rest[0]
            else:
                raise SystemExit(f"{path}:{number}: expected 'key K DEB...', 'cmake NAME K' or "
                                 f"'python MODULE K'")
    return keys, cmake, python


def find_packages(root):
    packages = []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if d not in SKIP_DIRS and not d.startswith("."))
        if "CATKIN_IGNORE" in filenames:
            dirnames[:] = []
            continue
        if "package.xml" in filenames:
            packages.append(dirpath)
    return packages


def read_manifest(directory):
    tree = ET.parse(os.path.join(directory, "package.xml"))
    name = tree.getroot().findtext("name").strip()
    declared = {}
    for element in tree.getroot():
        if element.tag in ALL_TAGS and element.text:
            declared.setdefault(element.text.strip(), set()).add(element.tag)
    return name, declared


def strip_cmake_comments(text):
    return "\n".join(re.sub(r"#.*", "", line) for line in text.splitlines())


def cmake_calls(text):
    """(command, argument words, line, in_test_block) for each command call."""
    calls = []
    depth_test = []  # stack of booleans: is this if() a testing block
    for match in re.finditer(r"\b([A-Za-z_][A-Za-z0-9_]*)\s*\(([^()]*(?:\([^()]*\)[^()]*)*)\)", text):
        command = match.group(1).lower()
        args = match.group(2).split()
        line = text.count("\n", 0, match.start()) + 1
        if command == "if":
            depth_test.append(any(a in ("CATKIN_ENABLE_TESTING", "BUILD_TESTING") for a in args))
        elif command == "endif" and depth_test:
            depth_test.pop()
        calls.append((command, args, line, any(depth_test)))
    return calls


def cmake_files(directory, root):
    files = [os.path.join(directory, "CMakeLists.txt")]
    cmake_dir = os.path.join(directory, "cmake")
    if os.path.isdir(cmake_dir):
        files += sorted(os.path.join(cmake_dir, f) for f in os.listdir(cmake_dir)
                        if f.endswith(".cmake") or f.endswith(".cmake.in"))
    seen, queue = [], [f for f in files if os.path.isfile(f)]
    while queue:
        path = queue.pop(0)
        if path in seen:
            continue
        seen.append(path)
        with open(path) as f:
            text = strip_cmake_comments(f.read())
        for command, args, _, _ in cmake_calls(text):
            if command == "include" and args:
                target = args[0].replace("${CMAKE_CURRENT_SOURCE_DIR}", directory)
                target = os.path.normpath(os.path.join(os.path.dirname(path), target)
                                          if not os.path.isabs(target) else target)
                if target.startswith(root) and os.path.isfile(target):
                    queue.append(target)
    return seen


def cmake_requirements(directory, root):
    """[(cmake name or catkin component, kind, in_test, where)]; kind: cmake, catkin or pkgconfig."""
    found = []
    for path in cmake_files(directory, root):
        with open(path) as f:
            text = strip_cmake_comments(f.read())
        where_file = os.path.relpath(path, root)
        variables = {}
        for command, args, line, in_test in cmake_calls(text):
            where = f"{where_file}:{line}"
            if command == "set" and args:
                variables[args[0]] = args[1:]
            elif command in ("find_package", "find_dependency") and args:
                name = args[0]
                if "QUIET" in args or name in CMAKE_BUILTIN:
                    continue
                if name == "catkin" and "COMPONENTS" in args:
                    words = []
                    for word in args[args.index("COMPONENTS") + 1:]:
                        ref = re.fullmatch(r"\$\{(\w+)\}", word)
                        words += variables.get(ref.group(1), []) if ref else [word]
                    for component in words:
                        if component not in ("REQUIRED", "QUIET"):
                            found.append((component, "catkin", in_test, where))
                    continue
                found.append((name, "cmake", in_test, where))
                # A component packaged apart from the rest (e.g. OpenCV's contrib ximgproc).
                if "COMPONENTS" in args:
                    for component in args[args.index("COMPONENTS") + 1:]:
                        found.append((f"{name}:{component}", "component", in_test, where))
            elif command == "pkg_check_modules" and len(args) > 1:
                for module in args[1:]:
                    if module in ("REQUIRED", "QUIET", "IMPORTED_TARGET", "GLOBAL", "NO_CMAKE_PATH",
                                  "NO_CMAKE_ENVIRONMENT_PATH"):
                        continue
                    found.append((re.split(r"[<>=]", module)[0], "pkgconfig", in_test, where))
    return found


def python_files(directory):
    for dirpath, dirnames, filenames in os.walk(directory):
        dirnames[:] = sorted(d for d in dirnames if d not in SKIP_DIRS and not d.startswith("."))
        for name in sorted(filenames):
            path = os.path.join(dirpath, name)
            if name.endswith(".py"):
                yield path
            elif "." not in name and os.path.isfile(path):
                try:
                    with open(path, "rb") as f:
                        first = f.readline()
                except OSError:
                    continue
                if first.startswith(b"#!") and b"python" in first:
                    yield path


def python_imports(path):
    with open(path, encoding="utf-8") as f:
        tree = ast.parse(f.read(), filename=path)
    modules = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            modules += [(alias.name.split(".")[0], node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            modules.append((node.module.split(".")[0], node.lineno))
    return modules


def launch_references(directory):
    """(path, is_test, [(package, line)]) for every .launch/.test file: pkg="X" and $(find X)."""
    for dirpath, dirnames, filenames in os.walk(directory):
        dirnames[:] = sorted(d for d in dirnames if d not in SKIP_DIRS and not d.startswith("."))
        for name in sorted(filenames):
            if not (name.endswith(".launch") or name.endswith(".test")):
                continue
            path = os.path.join(dirpath, name)
            with open(path) as f:
                text = re.sub(r"<!--.*?-->", lambda m: "\n" * m.group(0).count("\n"), f.read(),
                              flags=re.S)
            refs = []
            for match in re.finditer(r'\bpkg="([A-Za-z0-9_]+)"|\$\(find ([A-Za-z0-9_]+)\)', text):
                refs.append((match.group(1) or match.group(2), text.count("\n", 0, match.start()) + 1))
            in_test = name.endswith(".test") or os.sep + "test" + os.sep in path
            yield path, in_test, refs


def local_python_modules(directory):
    names = set()
    for dirpath, dirnames, filenames in os.walk(directory):
        dirnames[:] = [d for d in dirnames if d not in SKIP_DIRS and not d.startswith(".")]
        names.update(f[:-3] for f in filenames if f.endswith(".py"))
        if "__init__.py" in filenames:
            names.add(os.path.basename(dirpath))
    return names


def check(root, map_path):
    keys, cmake_map, python_map = load_map(map_path)
    packages = find_packages(root)
    manifests = {d: read_manifest(d) for d in packages}
    workspace = {name for name, _ in manifests.values()}
    problems = []
    for directory in packages:
        name, declared = manifests[directory]

        def require(key, allowed, what, where):
            tags = declared.get(key, set())
            if not tags & allowed:
                kinds = "/".join(sorted(allowed))
                have = f" (declared only as {'/'.join(sorted(tags))})" if tags else ""
                problems.append(f"{name}: {what} needs <{kinds}>{key}</...> in package.xml{have}"
                                f" [{where}]")

        for cmake_name, kind, in_test, where in cmake_requirements(directory, root):
            if kind == "component":
                key = cmake_map.get(cmake_name)
                if key is None:
                    continue
            elif kind == "catkin":
                key = cmake_name
            elif cmake_name in workspace:
                key = cmake_name
            else:
                key = cmake_map.get(f"{kind}:{cmake_name}") or cmake_map.get(cmake_name)
                if key is None:
                    problems.append(f"{name}: {kind} '{cmake_name}' has no 'cmake' line in "
                                    f"{os.path.relpath(map_path, root)} [{where}]")
                    continue
            if key == name:
                continue
            require(key, ALL_TAGS if in_test else BUILD_TAGS, f"{kind} '{cmake_name}'", where)

        stdlib = set(sys.stdlib_module_names)
        local = local_python_modules(directory)
        for path in python_files(directory):
            rel = os.path.relpath(path, root)
            in_test = os.sep + "test" + os.sep in os.sep + os.path.relpath(path, directory)
            try:
                imports = python_imports(path)
            except SyntaxError as error:
                problems.append(f"{name}: {rel} does not parse: {error}")
                continue
            for module, line in imports:
                if module in stdlib or module in local or module == "__future__":
                    continue
                key = python_map.get(module, module)
                if key == name:
                    continue
                require(key, ALL_TAGS if in_test else EXEC_TAGS, f"import {module}", f"{rel}:{line}")

        for path, in_test, referenced in launch_references(directory):
            for key, line in referenced:
                if key != name:
                    require(key, ALL_TAGS if in_test else EXEC_TAGS, f"launch reference {key}",
                            f"{os.path.relpath(path, root)}:{line}")

        for key in declared:
            if key not in workspace and key not in keys:
                problems.append(f"{name}: declared key '{key}' has no 'key' line (Debian packages) in "
                                f"{os.path.relpath(map_path, root)}")
    return problems, manifests, keys, workspace


def main():
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=repo)
    parser.add_argument("--map", default=None, help="default: <root>/scripts/rosdep_debian.txt")
    parser.add_argument("--list-debian", action="store_true")
    args = parser.parse_args()
    root = os.path.abspath(args.root)
    map_path = args.map or os.path.join(root, "scripts", "rosdep_debian.txt")
    problems, manifests, keys, workspace = check(root, map_path)
    if args.list_debian:
        debs = []
        for _, declared in manifests.values():
            for key in declared:
                for deb in keys.get(key, []) if key not in workspace else []:
                    if deb not in debs:
                        debs.append(deb)
        print("\n".join(sorted(debs)))
        return 1 if any("no 'key' line" in p for p in problems) else 0
    for problem in problems:
        print(problem)
    print(f"check_package_deps: {len(manifests)} packages, {len(problems)} gaps")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
