#!/usr/bin/env python3
"""Checks that no core library links LCM.

Reads the table CMake writes (core_libraries.tsv: name, archive, link closure) and fails when a
core library
  - links LCM, the message types or the node runtime (by its link closure), or
  - uses them anyway (by its archive's symbols: an undefined lcm_* or lcm:: symbol, or a
    message type's code compiled in).
"""
import re
import subprocess
import sys

FORBIDDEN_TARGETS = {"sarmap_runtime", "sarmap_lcmtypes", "PkgConfig::LCM", "lcm"}
LCM_SYMBOL = re.compile(r"^(lcm_\w+|lcm::\S+)")
MESSAGE_SYMBOL = re.compile(r"\bsarmap::\w+_t::")


def closure_problems(closure):
    bad = []
    for lib in closure:
        if lib in FORBIDDEN_TARGETS or re.search(r"(^|/)liblcm\.", lib):
            bad.append(lib)
    return bad


def symbol_problems(archive):
    out = subprocess.run(["nm", "-C", archive], capture_output=True, text=True)
    if out.returncode != 0:
        return ["nm failed: " + out.stderr.strip()]
    bad = set()
    for line in out.stdout.splitlines():
        parts = line.split(None, 2)
        if len(parts) < 2:
            continue
        symbol = parts[-1]
        kind = parts[-2] if len(parts) >= 2 else ""
        if kind == "U" and LCM_SYMBOL.match(symbol):
            bad.add("uses " + symbol)
        elif MESSAGE_SYMBOL.search(symbol):
            bad.add("contains message code " + symbol.split("(")[0])
    return sorted(bad)


def main():
    if len(sys.argv) != 2:
        print("usage: check_core_links.py core_libraries.tsv", file=sys.stderr)
        return 2
    failures = 0
    cores = 0
    with open(sys.argv[1]) as table:
        for line in table:
            fields = line.rstrip("\n").split("\t")
            if len(fields) < 2:
                continue
            name, archive = fields[0], fields[1]
            closure = fields[2].split() if len(fields) > 2 else []
            cores += 1
            problems = ["links " + lib for lib in closure_problems(closure)]
            problems += symbol_problems(archive)
            if problems:
                failures += 1
                print(f"FAIL {name}:")
                for p in problems[:10]:
                    print("   ", p)
            else:
                print(f"ok   {name} ({len(closure)} libraries linked, none of them LCM)")
    if cores == 0:
        print("no core libraries listed", file=sys.stderr)
        return 1
    print(f"{cores - failures} of {cores} core libraries are LCM-free")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
