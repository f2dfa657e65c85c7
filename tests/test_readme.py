"""The README's code runs as written.

Every ```python block of README.md is run on its own, in a fresh namespace, from an empty
working folder beside which `../shared` leads to the checkout's shared data (so paths written
as `../shared/data/mot17/...` work as they do from the checkout). A block is not run when:

- it is a transcript: a line starts with `$ ` or `>>> ` (output shown, not a program);
- an HTML comment on the line before its fence says so: `<!-- readme-test: skip REASON -->`;
- it needs the MOT17 data (it names `../shared/data`, `OCCTRACK_DATA` or a `MOT17-` sequence)
  and the data is missing: it skips with that reason (and fails in CI, as every data test).

Shell blocks (```sh) are not run (they install packages and take minutes), but every
`occtrack ...` command in them must parse: the subcommand exists and its options are known.
OCCTRACK_README points the test at another file (to check a proposed README before it lands).
"""

from __future__ import annotations

import os
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import pytest

from conftest import CHECKOUT, data_missing, mot17_root

README = Path(os.environ.get("OCCTRACK_README") or CHECKOUT / "README.md")
FENCE = re.compile(r"^```\s*([\w+-]*)\s*$")
SKIP_MARK = re.compile(r"<!--\s*readme-test:\s*skip\b\s*(.*?)\s*-->")
DATA_MARKS = ("../shared/data", "OCCTRACK_DATA", "MOT17-")


@dataclass(frozen=True)
class Block:
    language: str
    line: int  # of the opening fence, 1-based
    code: str
    skip: str | None  # the reason given in a readme-test comment, if any

    def __str__(self) -> str:
        return f"{README.name}:{self.line}"


def blocks(text: str) -> list[Block]:
    found, lines = [], text.splitlines()
    i = 0
    while i < len(lines):
        match = FENCE.match(lines[i])
        if not match or not lines[i].startswith("```"):
            i += 1
            continue
        start, language = i, match.group(1).lower()
        end = start + 1
        while end < len(lines) and not lines[end].startswith("```"):
            end += 1
        before = lines[start - 1] if start else ""
        mark = SKIP_MARK.search(before)
        found.append(Block(language, start + 1, "\n".join(lines[start + 1:end]) + "\n",
                           (mark.group(1) or "marked skip") if mark else None))
        i = end + 1
    return found


ALL = blocks(README.read_text(encoding="utf-8")) if README.is_file() else []
PYTHON = [b for b in ALL if b.language in ("python", "py", "python3")]
SHELL = [b for b in ALL if b.language in ("sh", "bash", "shell", "console")]


def test_the_readme_has_python_to_run():
    assert README.is_file(), f"{README} not found"
    assert PYTHON, f"no ```python blocks in {README}"


@pytest.mark.parametrize("block", PYTHON, ids=str)
def test_python_block_runs_as_written(block, tmp_path, monkeypatch):
    if block.skip:
        pytest.skip(f"{block}: {block.skip}")
    prompts = [ln for ln in block.code.splitlines() if ln.startswith(("$ ", ">>> "))]
    if prompts:
        pytest.skip(f"{block}: a transcript ({prompts[0][:20]!r}...), not a program")
    shared = CHECKOUT.parent / "shared"
    if any(mark in block.code for mark in DATA_MARKS):
        root, origin = mot17_root()
        if not root.is_dir():
            data_missing(f"{block} needs the MOT17 data: no {root} ({origin})")
    work = tmp_path / "work"
    work.mkdir()
    if shared.is_dir():
        (tmp_path / "shared").symlink_to(shared, target_is_directory=True)
    monkeypatch.chdir(work)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    code = compile(block.code, str(block), "exec")
    exec(code, {"__name__": "__readme__"})  # noqa: S102 - the README's own code


def occtrack_commands(block: Block) -> list[tuple[int, list[str]]]:
    """(line, argv) of every `occtrack ...` command in a shell block (after `$ ` prompts,
    `&&`, `;` and `|`), comments dropped, line continuations joined, and each shell variable
    replaced by 1 (a value of any type the option takes: a number, or a path's part)."""
    commands = []
    text = block.code.replace("\\\n", " ")
    for offset, raw in enumerate(text.splitlines(), start=1):
        line = raw[2:] if raw.startswith("$ ") else raw
        for part in re.split(r"&&|;|\|", line):
            try:
                words = shlex.split(part, comments=True)
            except ValueError:
                continue
            if words and words[0] == "occtrack":  # a shell variable stands for a value
                argv = [re.sub(r"\$\{?\w+\}?", "1", w) for w in words[1:]]
                commands.append((block.line + offset, argv))
    return commands


SHELL_COMMANDS = [(f"{README.name}:{line}", argv) for b in SHELL
                  for line, argv in occtrack_commands(b)]


@pytest.mark.parametrize(("where", "argv"), SHELL_COMMANDS, ids=[w for w, _ in SHELL_COMMANDS])
def test_shell_commands_name_real_subcommands_and_options(where, argv, capsys):
    from occtrack.cli import _command_of, build_parser

    parser = build_parser(_command_of(argv))
    try:
        parser.parse_args(argv)
    except SystemExit as exit_:
        err = capsys.readouterr().err
        assert exit_.code == 0, f"{where}: occtrack {' '.join(argv)}: {err.strip()}"


def test_the_block_finder_reads_fences_marks_and_prompts():
    text = ("# t\n```python\nx = 1\n```\n<!-- readme-test: skip needs a camera -->\n"
            "```python\nimport cv2\n```\n```sh\n$ occtrack demo --seed 1 && ls\n```\n")
    found = blocks(text)
    assert [(b.language, b.line, b.skip) for b in found] == [
        ("python", 2, None), ("python", 6, "needs a camera"), ("sh", 9, None)]
    assert occtrack_commands(found[2]) == [(10, ["demo", "--seed", "1"])]
