#!/usr/bin/env python3
"""Runs the docs' runnable commands as a reader would, and checks the docs' links.

  run_docs_commands.py --bin BIN_DIR [--python PY_DIR] PAGE...     run each page's blocks
  run_docs_commands.py --links PAGE...                             check relative links
  run_docs_commands.py --list PAGE...                              list the runnable blocks

A runnable block is a fenced block whose info string has `run` after its language:

    ```sh run                 (bash -euo pipefail)
    ```python run             (python3, PYTHONPATH=PY_DIR as after `make demo`)

Every page runs in a fresh, empty temporary folder outside the checkout, its blocks in order
(a tutorial's later steps use what earlier ones made), with BIN_DIR first on PATH, so the
commands are written as a user types them (`sweepmap sim ...`, not build/bin/sweepmap).
A block that exits non-zero fails the page with its file, line and output. Blocks without
`run` (real hardware, `make test`, long experiments) are documentation only.

--links: every relative link `[text](path#anchor)` of each page must name an existing file,
and an anchor one of the target page's headings (GitHub's anchors).
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List, NamedTuple, Set

FENCE = re.compile(r"^(\s*)(```+|~~~+)\s*([\w+-]*)\s*(.*)$")
RUNNERS = {"sh": ["bash", "-euo", "pipefail", "-c"], "bash": ["bash", "-euo", "pipefail", "-c"],
           "python": ["python3", "-c"]}
BLOCK_TIMEOUT_S = 600


class Block(NamedTuple):
    page: Path
    line: int  # of the opening fence, 1-based
    language: str
    runnable: bool
    text: str


def blocks(page: Path) -> List[Block]:
    """Every fenced block of a Markdown page."""
    out, lines, i = [], page.read_text().splitlines(), 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, marker, language, info = m.groups()
        body, j = [], i + 1
        while j < len(lines) and not lines[j].strip().startswith(marker):
            body.append(lines[j][len(indent):] if lines[j].startswith(indent) else lines[j])
            j += 1
        if j == len(lines):
            raise SystemExit(f"{page}:{i + 1}: code block never closed")
        out.append(Block(page, i + 1, language, "run" in info.split(), "\n".join(body) + "\n"))
        i = j + 1
    return out


def runnable(page: Path) -> List[Block]:
    found = [b for b in blocks(page) if b.runnable]
    for b in found:
        if b.language not in RUNNERS:
            raise SystemExit(f"{b.page}:{b.line}: a runnable block must be sh or python, "
                             f"not '{b.language}'")
    return found


def run_page(page: Path, bin_dir: Path, python_dir: Path, checkout: Path) -> bool:
    todo = runnable(page)
    if not todo:
        print(f"{page}: no runnable block")
        return True
    work = Path(tempfile.mkdtemp(prefix="sweepmap-docs-run-"))
    if checkout in work.parents:
        raise SystemExit(f"{work} is inside the checkout {checkout}: set TMPDIR elsewhere")
    env = dict(os.environ)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONPATH"] = str(python_dir)
    ok = True
    try:
        for b in todo:
            start = time.monotonic()
            print(f"--- {b.page}:{b.line} ({b.language}) in {work}\n{b.text}", end="", flush=True)
            try:
                r = subprocess.run(RUNNERS[b.language] + [b.text], cwd=work, env=env,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                   timeout=BLOCK_TIMEOUT_S)
                status, output = r.returncode, r.stdout
            except subprocess.TimeoutExpired as e:
                status, output = "timeout", (e.stdout or b"").decode(errors="replace")
            print(output, end="" if output.endswith("\n") or not output else "\n")
            print(f"--- {time.monotonic() - start:.1f} s, exit status {status}", flush=True)
            if status != 0:
                print(f"FAIL: {b.page}:{b.line}: exit status {status}")
                ok = False
                break
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return ok


def github_anchor(heading: str) -> str:
    text = heading.strip().replace("`", "")
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)
    return re.sub(r"[^\w\- ]", "", text.lower()).replace(" ", "-")


def anchors(page: Path) -> Set[str]:
    """The heading anchors GitHub gives a page (repeated headings get -1, -2, ...)."""
    seen: Dict[str, int] = {}
    out, in_code = set(), False
    for line in page.read_text().splitlines():
        if FENCE.match(line):
            in_code = not in_code
        if in_code:
            continue
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            a = github_anchor(m.group(1))
            n = seen.get(a, 0)
            out.add(a if n == 0 else f"{a}-{n}")
            seen[a] = n + 1
    return out


LINK = re.compile(r"(?<!\!)\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)|!\[[^\]]*\]\(([^)\s]+)\)")


def check_links(page: Path) -> List[str]:
    errors, in_code = [], False
    for n, line in enumerate(page.read_text().splitlines(), 1):
        if FENCE.match(line):
            in_code = not in_code
        if in_code:
            continue
        line = re.sub(r"`[^`]*`", "", line)
        for m in LINK.finditer(line):
            target = m.group(1) or m.group(2)
            if re.match(r"^[a-z]+:", target):
                continue  # http:, https:, mailto:
            path, _, anchor = target.partition("#")
            dest = (page.parent / path).resolve() if path else page
            if not dest.exists():
                errors.append(f"{page}:{n}: link to {target}: no such file {dest}")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                errors.append(f"{page}:{n}: link to {target}: no heading '#{anchor}' in {dest}")
    return errors


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("pages", nargs="+", type=Path)
    p.add_argument("--bin", type=Path, help="the build's bin folder, first on PATH")
    p.add_argument("--python", type=Path, help="the build's python folder, as PYTHONPATH")
    p.add_argument("--checkout", type=Path, default=Path(__file__).resolve().parents[2])
    p.add_argument("--links", action="store_true", help="check links instead of running")
    p.add_argument("--list", action="store_true", help="list the runnable blocks")
    a = p.parse_args()
    pages = [pg.resolve() for pg in a.pages]
    for pg in pages:
        if not pg.is_file():
            print(f"no such page: {pg}", file=sys.stderr)
            return 2
    if a.links:
        errors = [e for pg in pages for e in check_links(pg)]
        print("\n".join(errors) if errors else f"links of {len(pages)} pages resolve")
        return 1 if errors else 0
    if a.list:
        for pg in pages:
            for b in runnable(pg):
                print(f"{b.page}:{b.line}: {b.language}: {b.text.splitlines()[0] if b.text.strip() else ''}")
        return 0
    if not a.bin or not (a.bin / "sweepmap").exists():
        print("--bin must name the build's bin folder (with sweepmap)", file=sys.stderr)
        return 2
    python_dir = (a.python or a.bin.parent / "python").resolve()
    results = [run_page(pg, a.bin.resolve(), python_dir, a.checkout.resolve()) for pg in pages]
    return 0 if all(results) else 1


if __name__ == "__main__":
    sys.exit(main())
