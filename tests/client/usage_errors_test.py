#!/usr/bin/env python3
"""Runs every usage error docs/usage.md lists and holds shadowctl to its exit-code table.

docs/usage.md has a table of exit codes (0, 1, 2) and, after the marker
  <!-- usage-errors: ... -->
a table of commands, each with what shadowctl says on stderr. Each command runs with --server
pointing at a port this test listens on (after its subcommand, where it has one): it must exit
with the table's code for a usage error, say the text, and never connect, since usage errors
are found before any connection.

Usage: usage_errors_test.py USAGE_MD SHADOWCTL
"""

import pathlib
import re
import shlex
import socket
import subprocess
import sys
import tempfile
import threading

usage_md, shadowctl = pathlib.Path(sys.argv[1]), sys.argv[2]
text = usage_md.read_text()
failures = []


def table_after(heading_pattern):
    """The rows (lists of cells) of the first markdown table at or after the line that matches,
    without its header."""
    lines = text.splitlines()
    start = next(i for i, l in enumerate(lines) if re.search(heading_pattern, l))
    rows, i = [], start if lines[start].startswith("|") else start + 1
    while i < len(lines) and not lines[i].startswith("|"):
        i += 1
    while i < len(lines) and lines[i].startswith("|"):
        cells = [c.strip() for c in lines[i].strip().strip("|").split(" | ")]
        if not set(lines[i]) <= set("|- "):
            rows.append(cells)
        i += 1
    return rows[1:]  # without the header


def code(cell):
    m = re.fullmatch(r"`(.*)`", cell)
    if not m:
        failures.append(f"not a `code` cell: {cell}")
        return ""
    return m.group(1)


exits = {row[0]: row[1] for row in table_after(r"^\| exit \| when \|$")}
if sorted(exits) != ["0", "1", "2"]:
    failures.append(f"the exit-code table lists {sorted(exits)}, not 0, 1 and 2")
usage_exit = next((int(k) for k, v in exits.items() if v.startswith("a usage error")), None)
if usage_exit is None:
    failures.append("the exit-code table has no row for a usage error")
rows = table_after(r"^<!-- usage-errors:")
if len(rows) < 10:
    failures.append(f"only {len(rows)} usage errors listed")

# A port that counts connections: a usage error must not make one.
listener = socket.socket()
listener.bind(("127.0.0.1", 0))
listener.listen(16)
address = "127.0.0.1:%d" % listener.getsockname()[1]
connections = []


def accept():
    while True:
        try:
            conn, _ = listener.accept()
        except OSError:
            return
        connections.append(conn)


threading.Thread(target=accept, daemon=True).start()

with tempfile.TemporaryDirectory() as scratch:
    for command_cell, says_cell in rows:
        command, says = code(command_cell), code(says_cell)
        argv = shlex.split(command)
        if not argv or argv[0] != "shadowctl":
            failures.append(f"not a shadowctl command: {command}")
            continue
        argv[0] = shadowctl
        if len(argv) > 1 and not argv[1].startswith("-"):
            argv[2:2] = ["--server", address]
        before = len(connections)
        r = subprocess.run(argv, cwd=scratch, capture_output=True, text=True, timeout=60)
        if r.returncode != usage_exit:
            failures.append(f"{command}: exit {r.returncode}, not {usage_exit}: {r.stderr}")
        if says not in r.stderr:
            failures.append(f"{command}: stderr lacks {says!r}: {r.stderr!r}")
        if len(connections) != before:
            failures.append(f"{command}: connected to the server before refusing")
        if r.stdout:
            failures.append(f"{command}: printed on stdout: {r.stdout!r}")
        said = r.stderr.strip().splitlines()
        print(f"exit {r.returncode}: {command}\n    {said[0] if said else ''}")
listener.close()

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
