#!/usr/bin/env python3
"""Find the code GCC 12.2 miscompiles by dropping a single-precision rounding.

GCC 12.2 (Debian 12) folds a vectorized double -> float -> double conversion into nothing:
after its vectorizers turn

    P p{(float)a[0], (float)a[1]};  out[0] = p.x;  out[1] = p.y;

into `t = (vector(2) float) a; out = (vector(2) double) t`, the pair is simplified to
`out = a`, and the rounding to float is lost (cmake/NbvCompilerChecks.cmake detects the bug;
docs/performance-log.md has the details). This script compiles every source of a build again, as
compile_commands.json says, with GCC's dumps of its vectorizers, and lists each function in
which a vector truncated to float is widened back to double: the pattern GCC then folds away.

    scripts/find_float_roundtrips.py build

Exit status: 0 when no source has the pattern, 1 when some has (listed), 2 on bad input.
"""

import argparse
import concurrent.futures
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile

TRUNCATE = re.compile(r'^\s*(\S+) = \(vector\((\d+)\) float\) (\S+);')
WIDEN = re.compile(r'^\s*(\S+) = \(vector\((\d+)\) double\) (\S+);')
DUMPS = ["-fdump-tree-vect", "-fdump-tree-slp1", "-fdump-tree-slp2"]


def roundtrips_in_dump(path):
    """(function, statement) for each widening of a float vector truncated in that function."""
    found = []
    truncated, function = set(), "?"
    with open(path, errors="replace") as dump:
        for line in dump:
            if line.startswith(";; Function"):
                function, truncated = line[len(";; Function "):].strip(), set()
            elif (m := TRUNCATE.match(line)):
                truncated.add(m.group(1))
            elif (m := WIDEN.match(line)) and m.group(3) in truncated:
                found.append((function, line.strip()))
    return found


def arguments(entry):
    """The compiler and its arguments of one entry of compile_commands.json."""
    return entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])


def compile_with_dumps(entry, index, dump_dir):
    """Compiles one entry of compile_commands.json again with the dumps; returns their paths."""
    kept, skip = [], False
    for arg in arguments(entry):  # the object file is not written
        if skip:
            skip = False
        elif arg == "-o":
            skip = True
        else:
            kept.append(arg)
    prefix = os.path.join(dump_dir, f"{index}-")
    command = kept + DUMPS + ["-dumpdir", prefix, "-o", os.devnull]
    try:
        result = subprocess.run(command, cwd=entry["directory"], capture_output=True, text=True)
    except OSError as error:
        raise RuntimeError(f"{entry['file']}: cannot run the compiler: {error}") from error
    if result.returncode != 0:
        raise RuntimeError(f"{entry['file']}: the compiler failed:\n{result.stderr[-2000:]}")
    return [os.path.join(dump_dir, name) for name in os.listdir(dump_dir) if name.startswith(prefix[len(dump_dir) + 1:])]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("build_dir", help="a CMake build folder with compile_commands.json (GCC)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="compilers at a time")
    options = parser.parse_args()

    database = os.path.join(options.build_dir, "compile_commands.json")
    try:
        with open(database) as f:
            entries = json.load(f)
    except (OSError, json.JSONDecodeError) as error:
        print(f"find_float_roundtrips: cannot read {database}: {error}", file=sys.stderr)
        return 2
    if not entries:
        print(f"find_float_roundtrips: {database} lists no sources", file=sys.stderr)
        return 2

    compiler = arguments(entries[0])[0]
    try:
        version = subprocess.run([compiler, "--version"], capture_output=True, text=True).stdout
    except OSError as error:
        print(f"find_float_roundtrips: cannot run the compiler of {database}: {error}", file=sys.stderr)
        return 2
    if "clang" in version or "Free Software Foundation" not in version:
        print(f"{compiler} is not GCC: the audit is for GCC's vectorizers, nothing to do")
        return 0

    found = []
    with tempfile.TemporaryDirectory(prefix="nbv-roundtrips-") as dump_dir:
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, options.jobs)) as pool:
            jobs = {pool.submit(compile_with_dumps, e, i, dump_dir): e for i, e in enumerate(entries)}
            for job in concurrent.futures.as_completed(jobs):
                try:
                    dumps = job.result()
                except RuntimeError as error:
                    print(f"find_float_roundtrips: {error}", file=sys.stderr)
                    return 2
                for dump in dumps:
                    found += [(jobs[job]["file"], function, statement) for function, statement in roundtrips_in_dump(dump)]

    print(f"{len(entries)} sources compiled again with the vectorizers' dumps")
    if not found:
        print("no vector truncated to float is widened back to double: nothing for GCC 12.2 to fold away")
        return 0
    for source, function, statement in sorted(set(found)):
        print(f"{source}: {function}\n    {statement}")
    count = len(set(found))
    print(f"{count} {'place' if count == 1 else 'places'} where GCC 12.2 may drop a float rounding: build "
          "the source with -fno-tree-slp-vectorize (as NBV_PLAIN_LANES_FLAGS) or change the code")
    return 1


if __name__ == "__main__":
    sys.exit(main())
