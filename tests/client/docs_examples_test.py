#!/usr/bin/env python3
"""Runs every ```sh and ```python block of README.md and docs/usage.md, in order, as a user
would paste them at the repository's root, against a real server.

Which blocks run: all of them but those right after (blank lines aside) an HTML comment
  <!-- not run: REASON -->            (the reason is required and printed), or
  <!-- deploy-NAME: TEST runs ... --> (the deploy blocks: readme_deploy_test.sh and
                                      kubernetes_manifests_test.py run or check those).
The blocks run in one bash session, README's first, so the README's "Try it" block (which puts
build/ on PATH and starts shadow-server) serves the rest; python blocks run as files with
PYTHONPATH=build/client/python, as the README says. The session runs in a scratch directory
that mirrors the repository (its top-level entries linked, build/ linked to the build tree,
examples/ copied), and a free port stands for 127.0.0.1:50051 in every block.

Also checks that the blocks follow the docs' rules: every shadowctl render, sequence or stats
line names --server, and every --scene is builtin:demo or a file under examples/; and that
examples/make_examples.py would write exactly the files examples/ holds.

Usage: docs_examples_test.py SOURCE_DIR BUILD_DIR
"""

import os
import pathlib
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile

source, build = (pathlib.Path(p).resolve() for p in sys.argv[1:3])
DOCS = ["README.md", "docs/usage.md"]
ADDRESS = "127.0.0.1:50051"
failures = []


def blocks(relative):
    """(line, language, text, skip reason or None) for each fenced sh / python block."""
    lines = (source / relative).read_text().splitlines()
    found, i = [], 0
    while i < len(lines):
        m = re.match(r"^```(sh|python)\s*$", lines[i])
        if not m:
            i += 1
            continue
        j = i - 1
        while j >= 0 and not lines[j].strip():
            j -= 1
        marker = lines[j].strip() if j >= 0 else ""
        skip = None
        if marker.startswith("<!-- not run:"):
            skip = marker[len("<!-- not run:"):].removesuffix("-->").strip()
            if not skip:
                failures.append(f"{relative}:{j + 1}: 'not run' without a reason")
        elif re.match(r"<!-- deploy-[a-z]+:", marker):
            skip = marker[5:].removesuffix("-->").strip()
        end = next(k for k in range(i + 1, len(lines)) if lines[k].startswith("```"))
        found.append((i + 1, m.group(1), "\n".join(lines[i + 1:end]) + "\n", skip))
        i = end + 1
    return found


def check_rules(where, text):
    joined = text.replace("\\\n", " ")
    for line in joined.splitlines():
        words = shlex.split(line, comments=True) if "shadowctl" in line else []
        for k, w in enumerate(words):
            if w == "shadowctl" and k + 1 < len(words) and words[k + 1] in (
                    "render", "sequence", "stats"):
                if "--server" not in words[k:]:
                    failures.append(f"{where}: shadowctl {words[k + 1]} without --server")
        for scene in re.findall(r"--scene\s+(\S+)", line):
            if scene != "builtin:demo" and not (scene.startswith("examples/") and
                                                (source / scene).is_file()):
                failures.append(f"{where}: --scene {scene} is neither builtin:demo nor a file "
                                "under examples/")


# examples/ is what its script writes.
check = subprocess.run([sys.executable, str(source / "examples/make_examples.py"), "--check"],
                       capture_output=True, text=True)
if check.returncode != 0:
    failures.append(check.stdout.strip() or check.stderr.strip())

runs = []
for doc in DOCS:
    for line, language, text, skip in blocks(doc):
        where = f"{doc}:{line}"
        if skip is not None:
            print(f"skip  {where} ({language}): {skip}")
            continue
        check_rules(where, text)
        runs.append((where, language, text))
print(f"{len(runs)} blocks to run")

with socket.socket() as s:
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
work = pathlib.Path(tempfile.mkdtemp(prefix="docs-examples-"))
try:
    root = work / "repo"
    root.mkdir()
    for entry in source.iterdir():
        if entry.name in ("build", "out", "run", "examples", ".git") or entry.name.startswith("build-"):
            continue
        (root / entry.name).symlink_to(entry)
    (root / "build").symlink_to(build)
    shutil.copytree(source / "examples", root / "examples")
    script = ["set -euo pipefail",
              "trap 'jobs -p | xargs -r kill 2>/dev/null || true' EXIT",
              "trap 'echo \"docs_examples: FAILED in the block at $block\" >&2' ERR"]
    for n, (where, language, text) in enumerate(runs):
        text = text.replace(ADDRESS, f"127.0.0.1:{port}")
        script.append(f"block={shlex.quote(where)}; echo \"### $block\"")
        if language == "sh":
            script.append(text)
        else:
            path = work / f"block{n}.py"
            path.write_text(text)
            script.append(f"PYTHONPATH=build/client/python {shlex.quote(sys.executable)} "
                          f"{shlex.quote(str(path))}")
    script.append("echo '### every block ran'")
    (work / "blocks.sh").write_text("\n".join(script) + "\n")
    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", str(build / "pocl-cache"))
    print(f"running them in {root} with 127.0.0.1:{port} for {ADDRESS}", flush=True)
    proc = subprocess.Popen(["bash", str(work / "blocks.sh")], cwd=root, env=env,
                            start_new_session=True)
    try:
        rc = proc.wait(timeout=240)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        rc = "a timeout (240 s)"
    if rc != 0:
        failures.append(f"the blocks failed with {rc}: see the output above")
    try:  # whatever the blocks left running (the server started in the background)
        os.killpg(proc.pid, signal.SIGTERM)
    except ProcessLookupError:
        pass
finally:
    shutil.rmtree(work, ignore_errors=True)

for f in failures:
    print("FAIL  " + f)
if failures:
    sys.exit(1)
print(f"docs examples: {len(runs)} blocks of {', '.join(DOCS)} ran")
