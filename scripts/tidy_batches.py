#!/usr/bin/env python3
"""Runs clang-tidy over a unity build's compile database with the sources outside the library
batched as well (scripts/check-tidy.sh calls it; docs/ci.md).

The library's components are unity batches already (COMBABC_UNITY=ON). The other sources (tests,
the CLI, benchmarks, examples, the Python module) are compiled one per translation unit, and each
of them parses and matches the same gtest, Eigen, CLI11 or pybind11 headers again: clang-tidy's
matchers walk every declaration of those headers, in every file. Here the files that share a
command line are checked eight at a time as one translation unit (a batch file that #includes
them, as CMake's unity batches do), so the headers are parsed and matched once per batch.

Test files reuse file-scope names (kBits, Toy, Case), which cannot share a translation unit: no
batch takes two files that declare the same name at namespace scope (file_scope_names), and a
batch that still does not compile is checked again one file at a time, so a clash costs time,
never a missed or a false warning. It prints the CPU time of all the clang-tidy runs.

usage: tidy_batches.py BUILD_DIR ROOT CLANG_TIDY JOBS -- BATCH_ARGS... -- SINGLE_ARGS...
A batch is checked with the configuration its files have (-config: the .clang-tidy of their
folder, tests/ and bench/ have their own) and BATCH_ARGS; a file alone with SINGLE_ARGS.
Prints every translation unit's clang-tidy output; exits 1 if any clang-tidy run failed.
"""
import concurrent.futures
import json
import os
import re
import shlex
import subprocess
import sys

BATCH_SIZE = 8
# The project's own sources outside the library (which CMake batches itself).
OWN = r"/(apps|tests|bench|examples|python)/.*\.cpp$"
LIBRARY_BATCH = r"/src/CMakeFiles/[^/]+/Unity/unity_[0-9]+_cxx\.cxx$"
COMPILE_ERROR = re.compile(r": error: .*\[clang-diagnostic-error\]")
TEST_MACRO = re.compile(r"^(TEST|TEST_F|TEST_P|TYPED_TEST)\((\w+),\s*(\w+)")
INSTANTIATE = re.compile(r"^INSTANTIATE_TEST_SUITE_P\((\w+),\s*(\w+)")


def file_scope_names(path):
    """The names a file declares at namespace scope, roughly: what two files of one batch must not
    both declare. clang-format (Google style) leaves namespace scope unindented, so those are the
    declarations that start a line; a name missed here only costs the batch's retry."""
    names, raw = set(), False
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            # Lines inside a raw string literal (a config's text) declare nothing.
            was_raw = raw
            for mark in re.findall(r'R"\(|\)"', line):
                raw = mark != ')"'
            if was_raw:
                continue
            if m := TEST_MACRO.match(line):
                names.add("%s_%s_Test" % (m.group(2), m.group(3)))
            elif m := INSTANTIATE.match(line):
                names.add("instantiate %s %s" % (m.group(1), m.group(2)))
            elif m := re.match(r"#\s*define\s+(\w+)", line):
                names.add(m.group(1))
            elif re.match(r"[A-Za-z_]", line) and not re.match(
                    r"(namespace|using namespace|template\b|extern\b|[A-Z_]+\()", line):
                head = re.split(r"[({=;]| : ", line, maxsplit=1)[0]
                while re.search(r"<[^<>]*>", head):
                    head = re.sub(r"<[^<>]*>", "", head)
                if ids := re.findall(r"[A-Za-z_]\w*", head):
                    names.add(ids[-1])
                # And every name before an '=' (constexpr int kData = 65, kConfig = 78;).
                names.update(re.findall(r"([A-Za-z_]\w*)(?:\[\])?\s*=(?!=)", line))
    return names


def pack(files):
    """Batches of at most BATCH_SIZE files, no two of which declare the same name."""
    batches = []
    for e in files:
        names = file_scope_names(e["file"])
        for b in batches:
            if len(b[0]) < BATCH_SIZE and not b[1] & names:
                b[0].append(e)
                b[1] |= names
                break
        else:
            batches.append([[e], set(names)])
    return [b[0] for b in batches]


def key_of(entry):
    """The command line without its source and output: files with equal keys can share a TU."""
    args = entry.get("arguments") or shlex.split(entry["command"])
    out, skip = [], False
    for a in args:
        if skip:
            skip = False
        elif a == "-o":
            skip = True
        elif a == entry["file"] or a == "-c":
            continue
        else:
            out.append(a)
    return entry["directory"], tuple(out)


def config_dir(path, root):
    """The folder of the .clang-tidy that applies to `path` (tests/ and bench/ have their own)."""
    folder = os.path.dirname(path)
    while folder.startswith(root) and not os.path.exists(os.path.join(folder, ".clang-tidy")):
        folder = os.path.dirname(folder)
    return folder if folder.startswith(root) else root


def plan(build, root):
    """Writes BUILD/tidy-batches/ (batch files and a compile database); returns the work list of
    (path, members, config folder) triples: members is None for a single file, [] for a library
    batch."""
    with open(os.path.join(build, "compile_commands.json"), encoding="utf-8") as f:
        db = json.load(f)
    own = re.compile("^" + re.escape(root) + OWN)
    groups, work, entries = {}, [], []
    for e in db:
        if own.search(e["file"]):
            # One batch, one configuration: the files' own .clang-tidy (tests/ has no analyzer).
            groups.setdefault(key_of(e) + (config_dir(e["file"], root),), []).append(e)
        elif re.search(LIBRARY_BATCH, e["file"]):
            work.append((e["file"], [], root))
            entries.append(e)
        elif e["file"].startswith(root + "/src/"):
            work.append((e["file"], None, None))
            entries.append(e)
    out = os.path.join(build, "tidy-batches")
    os.makedirs(out, exist_ok=True)
    n = 0
    for (directory, args, folder), files in sorted(groups.items(), key=lambda g: g[1][0]["file"]):
        files.sort(key=lambda e: e["file"])
        for chunk in pack(files):
            if len(chunk) == 1:
                work.append((chunk[0]["file"], None, None))
                entries.append(chunk[0])
                continue
            path = os.path.join(out, "batch_%02d.cxx" % n)
            n += 1
            text = "".join('#include "%s"\n' % e["file"] for e in chunk)
            if not os.path.exists(path) or open(path, encoding="utf-8").read() != text:
                with open(path, "w", encoding="utf-8") as f:
                    f.write(text)
            entries.append({"directory": directory, "file": path,
                            "arguments": list(args) + ["-c", path]})
            entries.extend(chunk)  # for the one-file-at-a-time retry
            work.append((path, [e["file"] for e in chunk], folder))
    with open(os.path.join(out, "compile_commands.json"), "w", encoding="utf-8") as f:
        json.dump(entries, f, indent=1)
    return out, work


def main():
    argv = sys.argv[1:]
    first = argv.index("--")
    second = argv.index("--", first + 1)
    build, root, tidy, jobs = argv[:first]
    batch_args, single_args = argv[first + 1:second], argv[second + 1:]
    db, work = plan(os.path.abspath(build), root)

    configs = {}  # folder -> the configuration clang-tidy reads for a file there

    def config_of(folder):
        if folder not in configs:
            configs[folder] = subprocess.run(
                [tidy, "--dump-config", os.path.join(folder, "any.cpp"), "--"],
                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, check=True).stdout
        return configs[folder]

    def run(path, folder):
        """clang-tidy on one translation unit (a batch when `folder` names its configuration):
        its exit code, output and CPU seconds."""
        cmd = [tidy, "-p", db] + (batch_args + ["-config=" + config_of(folder)]
                                  if folder else single_args) + [path]
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        text = p.stdout.read()
        p.stdout.close()
        _, status, usage = os.wait4(p.pid, 0)  # this child's own CPU time
        p.returncode = os.waitstatus_to_exitcode(status)
        return p.returncode, text, usage.ru_utime + usage.ru_stime

    def check(item):
        path, members, folder = item
        code, text, cpu = run(path, folder)
        if members and COMPILE_ERROR.search(text):
            # A clash between the batch's files: each on its own, as without batches.
            text = "check-tidy: %s does not compile as one unit; its %d files one at a time\n" % (
                os.path.basename(path), len(members))
            code = 0
            for m in members:
                c, t, seconds = run(m, None)
                code, text, cpu = code or c, text + t, cpu + seconds
        if os.environ.get("COMBABC_TIDY_TIMES"):  # each unit's CPU, to measure (docs/ci.md)
            text += "check-tidy: %.1f s of CPU: %s %s\n" % (
                cpu, path, " ".join(os.path.relpath(m, root) for m in members or []))
        return code, text, cpu

    failed, total = False, 0.0
    # Batches first: the longest runs start first, and the singles fill the tail.
    work.sort(key=lambda w: w[1] is None)
    with concurrent.futures.ThreadPoolExecutor(int(jobs)) as pool:
        for code, text, cpu in pool.map(check, work):
            sys.stdout.write(text)
            sys.stdout.flush()
            failed, total = failed or code != 0, total + cpu
    batches = [w for w in work if w[1]]
    print("check-tidy: %d translation units (%d of them batches of %d files outside the library),"
          " %.0f s of CPU" % (len(work), len(batches), sum(len(w[1]) for w in batches), total))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
