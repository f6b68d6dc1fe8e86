#!/usr/bin/env python3
"""Runs the documentation's runnable snippets, so that the docs cannot drift from the program.

A fenced block is runnable when the line just before its opening fence is exactly

    <!-- runnable -->

(an HTML comment: invisible on GitHub and in any Markdown viewer). Languages: `sh`/`bash` (run by
`bash -euo pipefail`, so any failing command fails the snippet) and `python` (run by the Python
that has the built module, or skipped with a message when there is none). docs/ci.md, "Runnable
snippets", says which snippets to mark and how they run.

The runnable snippets of one Markdown file run in order, as a reader follows them, in one scratch
copy of the repository root: `examples/` copied (so that runs write their outputs there, not into
the source tree), the other top-level folders linked, the just-built CLI on PATH as `combabc` and
at `build-demo/apps/combabc` (where scripts/demo.sh builds it). A snippet that fails is reported as
FILE:LINE (of the line that failed, for shell snippets), with its output; the script exits 1.

Besides, every option written after `combabc COMMAND` anywhere in these files, runnable or not,
must be an option of `combabc COMMAND --help` (an option renamed or removed cannot linger in an
example nobody runs).

Usage:
  run_snippets.py --source-dir ROOT --combabc CLI [--python PY --pythonpath DIR] [--verbose]
                  [FILE...]      (default: README.md, docs/*.md, every .md under examples/)
  run_snippets.py ... --expect-failure FILE:LINE:KIND ... FILE
      the self-test: passes only if exactly these failures are found (KIND: snippet, option or
      marker), on a fixture that drifted, so the checks are shown to catch drift.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

MARKER = "<!-- runnable -->"
LANGUAGES = {"sh": "shell", "bash": "shell", "python": "python"}
# The repository's top-level folders a snippet may read (linked, not copied).
LINKED = ("apps", "cmake", "docs", "include", "python", "scripts", "src", "tests")


class Snippet:
    def __init__(self, path, line, language, code):
        self.path = path  # as given on the command line
        self.line = line  # 1-based line of the opening fence
        self.language = language
        self.code = code

    def where(self, offset=0):
        return f"{self.path}:{self.line + offset}"


def extract(path, text):
    """The runnable snippets of one Markdown file; a marker not followed by a known fence is an
    error (a mistyped marker must not silently turn a check off)."""
    snippets, errors = [], []
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if line.rstrip() != MARKER:  # exactly; an indented one is an example of it
            continue
        fence = lines[i + 1] if i + 1 < len(lines) else ""
        match = re.fullmatch(r"```(\w+)\s*", fence)
        if not match or match.group(1) not in LANGUAGES:
            errors.append((f"{path}:{i + 1}", "marker",
                           f"'{MARKER}' must be followed by a ```sh, ```bash or ```python "
                           f"fence, found '{fence}'"))
            continue
        end = next((j for j in range(i + 2, len(lines)) if lines[j].startswith("```")), None)
        if end is None:
            errors.append((f"{path}:{i + 2}", "marker", "runnable block has no closing fence"))
            continue
        snippets.append(Snippet(path, i + 2, LANGUAGES[match.group(1)],
                                "\n".join(lines[i + 2:end]) + "\n"))
    return snippets, errors


def cli_options(combabc):
    """{command or None: the options of `combabc [command] --help`}."""
    def options(arguments):
        text = subprocess.run([combabc] + arguments + ["--help"], check=True, text=True,
                              stdout=subprocess.PIPE).stdout
        found = set()
        for match in re.finditer(r"^  (-\w)?,?(--[\w-]+)?", text, re.M):
            found.update(name for name in match.groups() if name)
        return found, text

    top, text = options([])
    commands = re.findall(r"^  ([a-z]+) ", text.split("Subcommands:")[1], re.M)
    result = {None: top}
    for command in commands:
        result[command] = options([command])[0]
    return result


def check_options(path, text, options):
    """Every option written after `combabc COMMAND` anywhere in a doc (code, inline code or
    prose, up to a comment, pipe, separator or closing backtick) is an option of that command."""
    problems = []
    commands = "|".join(c for c in options if c)
    pattern = re.compile(r"(?<![\w.-])(?:[\w./-]*/)?combabc(?=\s|$)(?:\s+(" + commands
                         + r")\b)?([^#|;&)`\n]*)")
    lines = text.split("\n")
    for number, line in enumerate(lines, 1):
        # A shell line continued with a backslash: its options are on the next lines.
        joined, k = line, number
        while joined.endswith("\\") and k < len(lines):
            joined, k = joined[:-1] + " " + lines[k], k + 1
        for match in pattern.finditer(joined):
            command, rest = match.group(1), match.group(2)
            for token in rest.split():
                token = token.strip("[],.'\"")
                if not re.fullmatch(r"--?[A-Za-z][\w-]*(=.*)?", token):
                    continue
                option = token.split("=")[0]
                if option not in options[command]:
                    named = f"combabc {command + ' ' if command else ''}"
                    problems.append((f"{path}:{number}", "option",
                                     f"'{named}{option}': no such option ({named}--help)"))
    return problems


def documentation(source_dir):
    """README.md, docs/*.md and every Markdown file under examples/, relative to source_dir."""
    files = ["README.md"]
    for folder in ("docs", "examples"):
        for directory, subfolders, names in os.walk(os.path.join(source_dir, folder)):
            subfolders[:] = sorted(d for d in subfolders if not d.startswith("results"))
            files += sorted(os.path.relpath(os.path.join(directory, name), source_dir)
                            for name in names if name.endswith(".md"))
    return files


def scratch_checkout(source_dir, combabc):
    """A scratch copy of the repository root, as a reader's checkout after scripts/demo.sh."""
    root = tempfile.mkdtemp(prefix="combabc-snippets-")
    shutil.copytree(os.path.join(source_dir, "examples"), os.path.join(root, "examples"),
                    ignore=shutil.ignore_patterns("results*", "__pycache__"))
    for name in LINKED:
        if os.path.isdir(os.path.join(source_dir, name)):
            os.symlink(os.path.join(source_dir, name), os.path.join(root, name))
    for folder in ("bin", os.path.join("build-demo", "apps")):
        os.makedirs(os.path.join(root, folder))
        os.symlink(combabc, os.path.join(root, folder, "combabc"))
    return root


def run(snippet, root, env, python, timeout, verbose):
    """Runs one snippet in root; returns None when it passed, else a report of the failure."""
    if snippet.language == "shell":
        # The ERR trap names the failing line; bash numbers the script's lines from 1.
        script = ("trap 'echo \"snippet line $LINENO failed\" >&2' ERR\n" + snippet.code)
        command = ["bash", "-euo", "pipefail", "-c", script, "snippet"]
    else:
        command = [python, "-c", snippet.code]
    try:
        result = subprocess.run(command, cwd=root, env=env, stdin=subprocess.DEVNULL,
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return (snippet.where(1), "snippet", f"timed out after {timeout} s")
    if verbose:
        print(result.stdout.rstrip())
    if result.returncode == 0:
        return None
    failed = re.findall(r"snippet line (\d+) failed", result.stdout)
    # The trap's own line is line 1 of the script; the snippet's first line is line 2.
    offset = int(failed[-1]) - 1 if failed else 1
    return (snippet.where(offset), "snippet",
            f"failed (exit {result.returncode}):\n" + result.stdout.rstrip())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--source-dir", required=True)
    parser.add_argument("--combabc", required=True, help="the built CLI")
    parser.add_argument("--python", default="", help="a python that imports the built module")
    parser.add_argument("--pythonpath", default="", help="where the built module is")
    parser.add_argument("--timeout", type=float, default=60.0, help="seconds per snippet")
    parser.add_argument("--verbose", action="store_true", help="print every snippet's output")
    parser.add_argument("--expect-failure", action="append", default=[],
                        metavar="FILE:LINE:KIND",
                        help="the self-test: exactly these failures, and no other")
    parser.add_argument("files", nargs="*",
                        help="Markdown files, relative to --source-dir (default: README.md, "
                             "docs/*.md and every .md under examples/)")
    args = parser.parse_args()
    source_dir = os.path.realpath(args.source_dir)
    files = args.files or documentation(source_dir)
    combabc = os.path.realpath(args.combabc)

    python = ""
    if args.python and args.pythonpath:
        probe = subprocess.run([args.python, "-c", "import combabc"], check=False,
                               env=dict(os.environ, PYTHONPATH=args.pythonpath),
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        python = args.python if probe.returncode == 0 else ""

    options = cli_options(combabc)
    failures, ran, skipped, start = [], 0, 0, time.monotonic()
    for path in files:
        with open(os.path.join(source_dir, path), encoding="utf-8") as f:
            text = f.read()
        snippets, errors = extract(path, text)
        failures += errors + check_options(path, text, options)
        if not snippets:
            continue
        root = scratch_checkout(source_dir, combabc)
        env = dict(os.environ, PATH=os.path.join(root, "bin") + os.pathsep + os.environ["PATH"],
                   MPLBACKEND="Agg", PYTHONDONTWRITEBYTECODE="1")
        if python:
            env["PYTHONPATH"] = os.path.realpath(args.pythonpath)
        try:
            for snippet in snippets:
                if snippet.language == "python" and not python:
                    print(f"{snippet.where()}: skipped: the Python module is not built "
                          f"(or does not import)")
                    skipped += 1
                    continue
                began = time.monotonic()
                failure = run(snippet, root, env, python, args.timeout, args.verbose)
                ran += 1
                print(f"{snippet.where()}: {'FAILED' if failure else 'ok'} "
                      f"({time.monotonic() - began:.1f} s)")
                if failure:
                    failures.append(failure)
        finally:
            shutil.rmtree(root, ignore_errors=True)

    sys.stdout.flush()
    for where, kind, message in failures:
        print(f"{where}: {kind} {message}", file=sys.stderr)
    print(f"{ran} snippets run, {skipped} skipped, {len(failures)} failed, "
          f"{time.monotonic() - start:.1f} s")
    if args.expect_failure:
        # The self-test: each failure expected, at its line, and nothing else.
        caught = sorted(f"{where}:{kind}" for where, kind, _ in failures)
        if caught == sorted(args.expect_failure):
            print(f"self-test passed: caught {', '.join(caught)}")
            return 0
        print(f"self-test FAILED: expected failures at {', '.join(sorted(args.expect_failure))}; "
              f"got {', '.join(caught) or 'none'}", file=sys.stderr)
        return 1
    if ran == 0 and not failures:
        print("no runnable snippet found: the marker or the file list is wrong", file=sys.stderr)
        return 1
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
