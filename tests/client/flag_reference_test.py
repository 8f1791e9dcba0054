#!/usr/bin/env python3
"""docs/usage.md against the programs' own --help, so the flag reference cannot drift.

Runs `shadowctl --help`, `shadowctl SUBCOMMAND --help` for every subcommand it lists, and
`shadow-server --help`, and takes each option's names from the start of its line (not the flags a
description mentions). docs/usage.md documents a program's flags in the tables of its section,
`## shadowctl flags` or `## shadow-server flags` (up to the next `## ` heading): a flag counts as
documented when it appears in the first cell of a table row there. Fails naming every flag a
--help prints that its section's tables lack, and every flag those tables list that no --help
prints (a flag that was removed or renamed). `--help` itself must be mentioned anywhere.

Usage: flag_reference_test.py docs/usage.md SHADOWCTL SHADOW_SERVER
"""

import pathlib
import re
import subprocess
import sys

usage_path, shadowctl, server = sys.argv[1:4]
usage = pathlib.Path(usage_path).read_text()

OPTION_LINE = re.compile(r"^ {2}((?:-\w,)?--[a-z0-9][a-z0-9-]*(?:,--[a-z0-9][a-z0-9-]*)*)")
FLAG = re.compile(r"--[a-z0-9][a-z0-9-]*")


def help_text(*args):
    run = subprocess.run(list(args) + ["--help"], capture_output=True, text=True, timeout=60)
    if run.returncode != 0:
        sys.exit(f"{' '.join(args)} --help exited {run.returncode}:\n{run.stdout}{run.stderr}")
    return run.stdout


def options(text):
    flags = set()
    for line in text.splitlines():
        m = OPTION_LINE.match(line)
        if m:
            flags.update(FLAG.findall(m.group(1)))
    return flags


def subcommands(text):
    names, inside = [], False
    for line in text.splitlines():
        if line.strip() == "Subcommands:":
            inside = True
        elif inside and re.match(r"^ {2}[a-z]", line):
            names.append(line.split()[0])
        elif inside and line.strip() and not line.startswith(" "):
            inside = False
    return names


def documented(heading):
    lines = usage.splitlines()
    try:
        start = lines.index(heading)
    except ValueError:
        sys.exit(f"docs/usage.md has no heading '{heading}'")
    flags = set()
    for line in lines[start + 1:]:
        if line.startswith("## "):
            break
        if line.startswith("|"):
            cells = line.split("|")
            if len(cells) > 2:
                flags.update(FLAG.findall(cells[1]))
    return flags


top = help_text(shadowctl)
commands = subcommands(top)
if not commands:
    sys.exit("shadowctl --help lists no subcommands")
programs = {
    "shadowctl": ("## shadowctl flags",
                  {f"shadowctl {c}": options(help_text(shadowctl, c)) for c in commands}
                  | {"shadowctl": options(top)}),
    "shadow-server": ("## shadow-server flags", {"shadow-server": options(help_text(server))}),
}

failures = []
for program, (heading, helps) in programs.items():
    docs = documented(heading)
    printed = set().union(*helps.values()) - {"--help"}
    print(f"{program}: {len(printed)} flags in --help ({', '.join(sorted(helps))}), "
          f"{len(docs)} in docs/usage.md '{heading}'")
    for flag in sorted(printed - docs):
        where = ", ".join(sorted(h for h, flags in helps.items() if flag in flags))
        failures.append(f"{flag} ({where} --help) is not in docs/usage.md's '{heading}' tables")
    for flag in sorted(docs - printed):
        failures.append(f"{flag} is in docs/usage.md's '{heading}' tables but no {program} "
                        f"--help prints it")
if not re.search(r"(?<![\w-])--help(?![\w-])", usage):
    failures.append("docs/usage.md does not mention --help")

for f in failures:
    print("FAIL  " + f)
if failures:
    sys.exit(1)
print("every flag --help prints is in docs/usage.md, and no other")
