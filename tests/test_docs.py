"""The documentation works as written (docs/design.md section 7): every relative link resolves,
nothing cites the old design file, and every ``bash`` and ``python`` block of README.md and
docs/*.md runs, on tiny inputs.

A block is tuned for the test by an HTML comment on the line before it:
``<!-- docs-test: sub "OLD" "NEW" [sub "OLD" "NEW" ...] -->`` replaces text first (each OLD must
occur), ``<!-- docs-test: skip REASON -->`` leaves the block out (the reason is the skip
message). The blocks of one file run in order in one temporary folder.
"""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: Files whose code blocks run.
RUN_FILES = ("README.md", *sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs").glob("*.md")))
#: Files whose links are checked.
LINK_FILES = (*RUN_FILES, "data/README.md", "experiments/README.md", "experiments/REPORT.md")
RUN_LANGUAGES = ("bash", "python")
_FENCE = re.compile(r"^```(\w*)\s*$")
_DIRECTIVE = re.compile(r"^<!--\s*docs-test:\s*(.*?)\s*-->\s*$")
_LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


@dataclass(frozen=True)
class Block:
    """One fenced code block: where it is, its language, its text after the directive."""

    file: str
    line: int
    language: str
    text: str
    skip: str | None


def parse_blocks(markdown: str, file: str = "<text>") -> list[Block]:
    """Fenced blocks of ``markdown`` with their ``docs-test`` directive applied.

    Raises
    ------
    ValueError
        On an unclosed fence, an unknown directive, or a ``sub`` whose OLD text is absent.
    """
    lines = markdown.splitlines()
    blocks, i = [], 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        start, language = i, m.group(1)
        j = i + 1
        while j < len(lines) and lines[j].strip() != "```":
            j += 1
        if j == len(lines):
            raise ValueError(f"{file}:{start + 1}: code block is not closed")
        text = "\n".join(lines[start + 1: j]) + "\n"
        before = lines[start - 1] if start > 0 else ""
        directive = _DIRECTIVE.match(before)
        skip = None
        if directive:
            words = shlex.split(directive.group(1))
            if words and words[0] == "skip":
                skip = " ".join(words[1:]) or "no reason given"
            else:
                if len(words) % 3 or any(w != "sub" for w in words[::3]):
                    raise ValueError(f"{file}:{start}: directive must be 'skip REASON' or 'sub \"OLD\" \"NEW\"' pairs")
                for k in range(0, len(words), 3):
                    old, new = words[k + 1], words[k + 2]
                    if old not in text:
                        raise ValueError(f"{file}:{start}: sub {old!r}: not in the block")
                    text = text.replace(old, new)
        blocks.append(Block(file, start + 1, language, text, skip))
        i = j + 1
    return blocks


def _runnable():
    for name in RUN_FILES:
        for block in parse_blocks((ROOT / name).read_text(encoding="utf-8"), name):
            if block.language in RUN_LANGUAGES:
                yield pytest.param(block, id=f"{name}:{block.line}")


# -- the parser itself


def test_parser_applies_substitutions_and_skips():
    text = ('intro\n<!-- docs-test: sub "--frames 300" "--frames 3" sub "a.mp4" "b" -->\n```bash\n'
            'run a.mp4 --frames 300\n```\n<!-- docs-test: skip needs a camera -->\n```python\nx = 1\n```\n'
            '```\nplain\n```\n')
    a, b, c = parse_blocks(text)
    assert (a.language, a.text, a.skip, a.line) == ("bash", "run b --frames 3\n", None, 3)
    assert (b.language, b.skip) == ("python", "needs a camera")
    assert (c.language, c.text) == ("", "plain\n")


@pytest.mark.parametrize("text, message", [
    ('<!-- docs-test: sub "absent" "x" -->\n```bash\necho hi\n```\n', "not in the block"),
    ('<!-- docs-test: frobnicate -->\n```bash\necho hi\n```\n', "directive must be"),
    ("```bash\necho hi\n", "not closed"),
])
def test_parser_rejects_stale_or_bad_directives(text, message):
    with pytest.raises(ValueError, match=message):
        parse_blocks(text)


# -- links and references


def test_relative_links_resolve():
    broken = []
    for name in LINK_FILES:
        path = ROOT / name
        for m in _LINK.finditer(path.read_text(encoding="utf-8")):
            target = m.group(1).split("#")[0]
            if not target or re.match(r"^[a-z]+:", target):
                continue
            if not (path.parent / target).exists():
                broken.append(f"{name}: {m.group(1)}")
    assert broken == []


#: Files allowed to still name the old design file (none: the code points at docs/design.md).
_OLD_DESIGN_ALLOWED: set[str] = set()


def test_nothing_cites_the_old_design_file():
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True).stdout.split()
    if not files:
        pytest.skip("not a git checkout")
    found = []
    for name in files:
        path = ROOT / name
        if name in _OLD_DESIGN_ALLOWED or path.suffix not in (".py", ".md", ".toml", ".ipynb", ".txt") or not path.is_file():
            continue
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if re.search(r"(?<![\w/])DESIGN\.md", line):
                found.append(f"{name}:{n}")
    assert found == [], "point these at docs/design.md"


def test_research_log_commits_exist():
    log = (ROOT / "docs" / "research-log.md").read_text(encoding="utf-8")
    hashes = sorted(set(re.findall(r"\b[0-9a-f]{7}\b", log)))
    assert hashes, "the research log cites no commit"
    probe = subprocess.run(["git", "rev-parse", "--git-dir"], cwd=ROOT, capture_output=True, text=True)
    if probe.returncode != 0:
        pytest.skip("not a git checkout")
    shallow = subprocess.run(["git", "rev-parse", "--is-shallow-repository"], cwd=ROOT, capture_output=True,
                             text=True).stdout.strip()
    if shallow == "true":
        pytest.skip("shallow clone: old commits are not there")
    missing = [h for h in hashes if subprocess.run(["git", "cat-file", "-e", f"{h}^{{commit}}"], cwd=ROOT,
                                                   capture_output=True).returncode != 0]
    assert missing == []


#: Most bytes the README may take (6 KB: a first page, the rest in docs/).
README_MAX_BYTES = 6 * 1024


def test_readme_is_at_most_6_kb_and_says_how_to_open_the_notebooks():
    text = (ROOT / "README.md").read_bytes()
    assert len(text) <= README_MAX_BYTES, f"README.md is {len(text)} bytes; move detail to docs/"
    assert b"jupyter lab notebooks/" in text and b"jupytext" in text


def _written_by_commands() -> set[str]:
    """Relative paths the documentation's commands and the notebooks write: every ``--out`` of a
    bash block (README.md, docs/*.md), the API snippet's output folder, the calibration
    notebook's file."""
    written = set()
    for name in RUN_FILES:
        text = (ROOT / name).read_text(encoding="utf-8")           # as written, not as the tests run it
        for block in parse_blocks(re.sub(r"(?m)^<!--\s*docs-test:.*-->$", "", text), name):
            if block.language == "bash":
                written.update(re.findall(r"--out\s+([\w.-]+(?:/[\w.-]+)*)", block.text))
            elif block.language == "python":
                written.update(re.findall(r"track\w*\([^,()]+(?:\(\))?,\s*\"([^\"]+)\"", block.text))
    notebook = (ROOT / "notebooks" / "calibration.py").read_text(encoding="utf-8")
    written.update(re.findall(r'"MOCAP_NOTEBOOK_OUT",\s*"([^"]+)"', notebook))
    return {w for w in written if w.upper() != w}           # not placeholders (DIR, JSON)


def test_what_the_commands_write_and_a_virtual_environment_are_git_ignored():
    written = _written_by_commands()
    assert {"my_track", "my_clip", "my_calibration.json", "api-demo", "calibration-notebook.json"} <= written
    probe = subprocess.run(["git", "rev-parse", "--git-dir"], cwd=ROOT, capture_output=True, text=True)
    if probe.returncode != 0:
        pytest.skip("not a git checkout")
    ignored = subprocess.run(["git", "check-ignore", "--no-index", "--stdin"], cwd=ROOT, capture_output=True,
                             text=True, input="\n".join(f"{w}/poses.csv" if "." not in w else w
                                                        for w in sorted(written))).stdout.split()
    assert sorted(w for w in written if (f"{w}/poses.csv" if "." not in w else w) not in ignored) == []
    # a virtual environment made in the checkout (python -m venv .venv) is ignored too
    venv = subprocess.run(["git", "check-ignore", "--no-index", ".venv/bin/python", ".venv/pyvenv.cfg"], cwd=ROOT,
                          capture_output=True, text=True).stdout.split()
    assert venv == [".venv/bin/python", ".venv/pyvenv.cfg"]


# -- the code blocks run


@pytest.fixture(scope="module")
def workdirs(tmp_path_factory):
    """One temporary folder per documentation file (its blocks share it, in order)."""
    return {name: tmp_path_factory.mktemp(Path(name).stem) for name in RUN_FILES}


@pytest.mark.slow
@pytest.mark.parametrize("block", list(_runnable()))
def test_code_block_runs(block, workdirs):
    if block.skip:
        pytest.skip(f"{block.file}:{block.line}: {block.skip}")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])),
           "MPLBACKEND": "Agg"}
    if block.language == "bash":
        cmd = ["bash", "-euo", "pipefail", "-c", block.text.replace("python -m", f"{shlex.quote(sys.executable)} -m")]
    else:
        cmd = [sys.executable, "-c", block.text]
    done = subprocess.run(cmd, cwd=workdirs[block.file], env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f"{block.file}:{block.line} failed:\n{block.text}\n{done.stdout[-2000:]}\n{done.stderr[-3000:]}"
