"""The README's and the docs' code runs as written, in the order a reader meets it.

Each page (README.md, every docs/*.md) is one test, so pytest-xdist never splits a page's
blocks across workers. A page gets one empty scratch folder and one Python namespace; its
blocks run top to bottom:

- ```python blocks are executed in the page's namespace (cwd: the scratch folder);
- ```bash / ```sh / ```shell blocks run with `bash -euo pipefail` in the scratch folder, with
  OCCTRACK_DATA set to the MOT17 folder (as tests/conftest.py finds it) and the running
  Python's bin folder first on PATH (so `occtrack` is this install's);
- other blocks (```toml, ```text, ```console, ...) are shown, not run.

`../shared/data/...` written in a block works as it does from the checkout: the scratch folder
sits in a temporary folder beside a `shared` link to the checkout's `../shared`.

Markers, an HTML comment on the line just before a block's opening fence:

- `<!-- docs-test: slow -->`: the block takes more than ~15 s. It runs only when
  OCCTRACK_DOCS_SLOW=1, in `test_page_runs_with_slow_blocks[PAGE]` (the whole page again,
  slow blocks included; .ci/run runs these). The normal run skips slow blocks and goes on:
  a later fast block must not need a slow block's output (docs/building-docs.md).
- `<!-- docs-test: output -->` or `<!-- docs-test: output ignore=REGEX -->` before a ```text
  block: the transcript of the block just before it, compared with what that block printed
  (stdout), trailing whitespace and blank edge lines stripped, REGEX matches masked on both
  sides.
- `<!-- docs-test: skip REASON -->`: never run (installs, `mkdocs serve`); the reason is
  printed.

A block naming OCCTRACK_DATA or ../shared/data when that data is missing stops its page there:
the test skips, naming the block and what did not run (and fails under CI=true, as every data
test does). Shell blocks that install packages, clone or run the test suite must be marked
skip; a test refuses to run them unmarked.

The other tests here: the README stays at most 250 lines and its relative links resolve;
every `occtrack ...` command written in a shell block parses; every subcommand (and
`reproduce` / `simulate` scene) has a section in docs/cli.md naming each of its options; every
page is in mkdocs.yml's nav. `python tests/test_docs.py` prints the blocks of every page.
"""

from __future__ import annotations

import contextlib
import difflib
import io
import os
import re
import shlex
import signal
import subprocess
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # conftest, when run as a script
from conftest import CHECKOUT, data_missing, mot17_root  # noqa: E402

DOCS = CHECKOUT / "docs"
README = CHECKOUT / "README.md"
PAGES = [README, *sorted(DOCS.glob("*.md"))]
SLOW = os.environ.get("OCCTRACK_DOCS_SLOW", "").strip().lower() in ("1", "true", "yes")
README_MAX_LINES = 250
FAST_TIMEOUT, SLOW_TIMEOUT = 600, 3600  # seconds a block may take
SLOW_WARNING = 30  # seconds: a fast block that takes longer is warned about (mark it slow)

PYTHON_LANGS = ("python", "py", "python3")
SHELL_LANGS = ("bash", "sh", "shell")
SHOWN_SHELL_LANGS = ("console", "shell-session")  # shown, not run; their commands must parse
OPEN = re.compile(r"^(?P<indent>[ \t]*)(?P<fence>`{3,}|~{3,})\s*\{?\s*\.?(?P<lang>[\w+-]*)")
MARK = re.compile(r"<!--\s*docs-test:\s*(?P<kind>[\w-]+)\b\s*(?P<arg>.*?)\s*-->")
MARK_KINDS = ("slow", "output", "skip")
DATA_MARKS = ("OCCTRACK_DATA", "shared/data")
# data sets beside the MOT17 folder, and the words that show a block uses one
DATA_SETS = ("mot17-yolox", "kitti", "laser")
# what a block run by the tests must not do: change the environment, reach the network, or
# run the test suite inside itself
UNRUNNABLE = re.compile(r"\bpip3?\s+(install|uninstall)\b|\bapt(-get)?\s+install\b|"
                        r"\bgit\s+clone\b|\bpytest\b|\bmkdocs\s+(serve|gh-deploy)\b")


@dataclass(frozen=True)
class Block:
    page: str  # path relative to the checkout
    language: str
    line: int  # of the opening fence, 1-based
    code: str
    mark: str | None = None  # slow, output, skip
    mark_arg: str = ""

    def __str__(self) -> str:
        return f"{self.page}:{self.line}"

    @property
    def python(self) -> bool:
        return self.language in PYTHON_LANGS

    @property
    def shell(self) -> bool:
        return self.language in SHELL_LANGS

    @property
    def runnable(self) -> bool:
        return self.python or self.shell

    @property
    def uses_data(self) -> bool:
        return any(mark in self.code for mark in DATA_MARKS)


def blocks(text: str, page: str = "page.md") -> list[Block]:
    """Every fenced block of a Markdown text, with the marker on the line before its fence."""
    found, lines = [], text.splitlines()
    i = 0
    while i < len(lines):
        match = OPEN.match(lines[i])
        if not match:
            i += 1
            continue
        indent, fence = match.group("indent"), match.group("fence")
        end = i + 1
        while end < len(lines) and not (lines[end].strip().startswith(fence)
                                        and lines[end].strip().strip(fence[0]) == ""):
            end += 1
        body = [ln[len(indent):] if ln.startswith(indent) else ln.lstrip()
                for ln in lines[i + 1:end]]
        before = MARK.search(lines[i - 1]) if i else None
        found.append(Block(page, match.group("lang").lower(), i + 1, "\n".join(body) + "\n",
                           before.group("kind") if before else None,
                           before.group("arg") if before else ""))
        i = end + 1
    return found


def page_blocks(path: Path) -> list[Block]:
    return blocks(path.read_text(encoding="utf-8"), str(path.relative_to(CHECKOUT)))


def fenced_lines(text: str) -> set[int]:
    """0-based indices of the lines inside (or fencing) code blocks."""
    inside, lines = set(), text.splitlines()
    for block in blocks(text):
        start = block.line - 1
        inside.update(range(start, start + block.code.count("\n") + 2))
    return {i for i in inside if i < len(lines)}


ALL = {path: page_blocks(path) for path in PAGES if path.is_file()}
PAGE_IDS = [str(p.relative_to(CHECKOUT)) for p in ALL]
SLOW_PAGES = [p for p, found in ALL.items() if any(b.mark == "slow" and b.runnable
                                                   for b in found)]


# -- running a page ----------------------------------------------------------------------------

@dataclass
class Run:
    """What happened to a page's blocks."""
    ran: list[str] = field(default_factory=list)
    not_run: list[str] = field(default_factory=list)  # "page:line (why)"
    timings: list[str] = field(default_factory=list)


def data_root() -> Path:
    root, _ = mot17_root()
    return root.resolve()


def needs_data(block: Block) -> str | None:
    """Why a block cannot run here (the data it names is missing), or None."""
    root, origin = mot17_root()
    if not root.is_dir():
        return f"{block} needs the MOT17 data: no {root} ({origin})"
    for name in DATA_SETS:
        if re.search(rf"(OCCTRACK_DATA\}}?|shared/data)/(\.\./)?{re.escape(name)}\b",
                     block.code) and not (root.parent / name).is_dir():
            return f"{block} needs {root.parent / name} (the {name} data beside MOT17)"
    return None


def run_python(block: Block, namespace: dict) -> str:
    """Run a Python block in the page's namespace; its stdout, echoed too. Traceback lines
    are the page's (the code is compiled at its place in the file)."""
    code = compile("\n" * block.line + block.code, str(CHECKOUT / block.page), "exec")
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            exec(code, namespace)  # noqa: S102 - the docs' own code
    except BaseException as err:
        sys.stdout.write(out.getvalue())
        if isinstance(err, KeyboardInterrupt):
            raise
        raise AssertionError(f"{block}: the Python block raised "
                             f"{type(err).__name__}: {err}") from err
    sys.stdout.write(out.getvalue())
    return out.getvalue()


def run_shell(block: Block, scratch: Path, env: dict, groups: list[int], timeout: float) -> str:
    """Run a shell block with bash -euo pipefail; its stdout. Output goes to files, not
    pipes, so a process the block leaves running cannot hold the test up; it is stopped at
    the end of the page."""
    logs = scratch.parent / "logs"
    logs.mkdir(exist_ok=True)
    script = logs / f"line{block.line}.sh"
    script.write_text(block.code, encoding="utf-8")
    out_path, err_path = logs / f"line{block.line}.out", logs / f"line{block.line}.err"
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        proc = subprocess.Popen(["bash", "-euo", "pipefail", str(script)], cwd=scratch,
                                env=env, stdin=subprocess.DEVNULL, stdout=out, stderr=err,
                                start_new_session=True)
        groups.append(proc.pid)
        try:
            status = proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            stop(proc.pid)
            proc.wait()
            status = None
    stdout = out_path.read_text(encoding="utf-8", errors="replace")
    stderr = err_path.read_text(encoding="utf-8", errors="replace")
    sys.stdout.write(stdout)
    sys.stderr.write(stderr)
    if status != 0:
        what = (f"took more than {timeout:.0f} s" if status is None
                else f"exited with status {status}")
        raise AssertionError(
            f"{block}: the shell block {what}\n--- block ---\n{block.code}"
            f"--- stderr (end) ---\n{stderr[-3000:]}\n--- stdout (end) ---\n{stdout[-1500:]}")
    return stdout


def stop(group: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(group, signal.SIGTERM)


def normalise(text: str, ignore: str) -> list[str]:
    lines = [ln.rstrip() for ln in text.splitlines()]
    while lines and not lines[0]:
        lines.pop(0)
    while lines and not lines[-1]:
        lines.pop()
    if ignore:
        lines = [re.sub(ignore, "<ignored>", ln) for ln in lines]
    return lines


def check_transcript(block: Block, source: Block, printed: str) -> None:
    ignore = ""
    if block.mark_arg:
        match = re.fullmatch(r"ignore=(['\"]?)(.*)\1", block.mark_arg)
        assert match, f"{block}: bad output marker argument {block.mark_arg!r} (ignore=REGEX)"
        ignore = match.group(2)
    want, got = normalise(block.code, ignore), normalise(printed, ignore)
    if want != got:
        diff = "\n".join(difflib.unified_diff(want, got, f"{block} (the page)",
                                              f"{source} printed now", lineterm=""))
        raise AssertionError(f"{block}: the transcript differs from what {source} prints "
                             f"now:\n{diff}")


def run_page(path: Path, tmp_path: Path, monkeypatch, slow: bool) -> Run:
    """Run a page's blocks in order (slow blocks only when `slow`); stop at a block whose data
    is missing (skip, or fail in CI)."""
    found, run = ALL[path], Run()
    scratch = tmp_path / "work"
    scratch.mkdir()
    shared = CHECKOUT.parent / "shared"
    if shared.is_dir():
        (tmp_path / "shared").symlink_to(shared, target_is_directory=True)
    env = dict(os.environ, OCCTRACK_DATA=str(data_root()), MPLBACKEND="Agg", COLUMNS="80",
               PATH=os.pathsep.join([str(Path(sys.executable).parent),
                                     os.environ.get("PATH", "")]))
    for name in ("PYTEST_XDIST_WORKER", "PYTEST_CURRENT_TEST", "OCCTRACK_DOCS_SLOW"):
        env.pop(name, None)
    monkeypatch.chdir(scratch)
    for name in ("OCCTRACK_DATA", "MPLBACKEND", "COLUMNS"):
        monkeypatch.setenv(name, env[name])
    namespace = {"__name__": "__main__"}
    groups: list[int] = []
    last: Block | None = None  # the last runnable block, and what it printed (None: not run)
    printed: str | None = None
    try:
        for i, block in enumerate(found):
            if block.mark == "output" and not block.runnable:
                if last is None:
                    raise AssertionError(f"{block}: an output marker with no block before it")
                if printed is None:
                    run.not_run.append(f"{block} (transcript of {last}, which did not run)")
                else:
                    check_transcript(block, last, printed)
                    run.ran.append(str(block))
                continue
            if not block.runnable:
                continue
            last, printed = block, None
            if block.mark == "skip":
                run.not_run.append(f"{block} (skip: {block.mark_arg or 'no reason given'})")
                continue
            if block.mark == "slow" and not slow:
                run.not_run.append(f"{block} (slow; OCCTRACK_DOCS_SLOW=1 runs it)")
                continue
            if block.shell and UNRUNNABLE.search(block.code):
                raise AssertionError(
                    f"{block}: installs, clones or runs the test suite: mark it "
                    f"<!-- docs-test: skip REASON --> (it cannot run inside the tests)")
            if block.uses_data:
                missing = needs_data(block)
                if missing:
                    rest = [str(b) for b in found[i:] if b.runnable]
                    data_missing(f"{missing}; stopped there, not run: {', '.join(rest)} "
                                 f"(ran: {', '.join(run.ran) or 'nothing'})")
            started = time.perf_counter()
            try:
                if block.python:
                    printed = run_python(block, namespace)
                else:
                    printed = run_shell(block, scratch, env, groups,
                                        SLOW_TIMEOUT if block.mark == "slow" else FAST_TIMEOUT)
            except AssertionError as err:
                skipped = [b for b in run.not_run if "(slow;" in b]
                if skipped:
                    raise AssertionError(
                        f"{err}\n(slow blocks before it were not run: {', '.join(skipped)}; a "
                        f"block that needs their output is slow too)") from err
                raise
            run.ran.append(str(block))
            took = time.perf_counter() - started
            run.timings.append(f"{block} {took:.1f} s")
            if block.mark != "slow" and took > SLOW_WARNING:
                warnings.warn(f"{block} took {took:.0f} s: mark it <!-- docs-test: slow --> "
                              f"(the 10-minute suite runs fast blocks only)", stacklevel=1)
    finally:
        for group in groups:
            stop(group)
        print(f"{path.name}: ran {run.ran}; not run {run.not_run}; timings {run.timings}")
    return run


@pytest.mark.parametrize("path", list(ALL), ids=PAGE_IDS)
def test_page_runs(path, tmp_path, monkeypatch):
    """Every fast block of the page, in order, in one folder and one namespace."""
    run_page(path, tmp_path, monkeypatch, slow=False)


@pytest.mark.parametrize("path", SLOW_PAGES,
                         ids=[str(p.relative_to(CHECKOUT)) for p in SLOW_PAGES])
def test_page_runs_with_slow_blocks(path, tmp_path, monkeypatch):
    """The whole page, slow blocks included (OCCTRACK_DOCS_SLOW=1; .ci/run sets it)."""
    if not SLOW:
        slow = [str(b) for b in ALL[path] if b.mark == "slow" and b.runnable]
        pytest.skip(f"{len(slow)} slow block(s) not run ({', '.join(slow)}); "
                    f"OCCTRACK_DOCS_SLOW=1 runs them")
    run_page(path, tmp_path, monkeypatch, slow=True)


# -- what the pages hold -------------------------------------------------------------------

def test_there_is_python_to_run():
    assert README.is_file(), f"{README} not found"
    assert any(b.python for found in ALL.values() for b in found), "no ```python block at all"
    assert any(b.python for b in ALL[README]), "no ```python block in README.md"


def test_the_markers_are_known_and_placed():
    problems = []
    for path in ALL:
        lines = path.read_text(encoding="utf-8").splitlines()
        inside = fenced_lines("\n".join(lines))
        fences = {b.line - 1: b for b in ALL[path]}
        page = path.relative_to(CHECKOUT)
        for i, line in enumerate(lines):
            mark = MARK.search(line)
            if not mark or i in inside:
                continue
            where = f"{page}:{i + 1}"
            block = fences.get(i + 1)
            if mark.group("kind") not in MARK_KINDS:
                problems.append(f"{where}: unknown marker {mark.group('kind')!r} "
                                f"(one of {', '.join(MARK_KINDS)})")
            elif block is None:
                problems.append(f"{where}: a marker must be on the line just before a fence")
            elif mark.group("kind") == "output" and block.language != "text":
                problems.append(f"{where}: an output marker belongs before a ```text block")
            elif mark.group("kind") in ("slow", "skip") and not block.runnable:
                problems.append(f"{where}: {mark.group('kind')} marks a block that is not run")
            elif mark.group("kind") == "skip" and not mark.group("arg"):
                problems.append(f"{where}: a skip marker needs its reason")
    assert not problems, "\n".join(problems)


def test_the_readme_is_short():
    lines = README.read_text(encoding="utf-8").count("\n")
    assert lines <= README_MAX_LINES, (f"README.md has {lines} lines (at most "
                                       f"{README_MAX_LINES}): move the rest into docs/")


def slugs(text: str) -> set[str]:
    """The anchors of a Markdown text's headings, as GitHub and as MkDocs make them, and
    attr_list ids ({#id})."""
    found, inside = set(), fenced_lines(text)
    for i, line in enumerate(text.splitlines()):
        match = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not match or i in inside:
            continue
        title = match.group(1)
        given = re.search(r"\{[^}]*#([\w-]+)[^}]*\}\s*$", title)
        if given:
            found.add(given.group(1))
            title = title[:given.start()]
        plain = re.sub(r"[`*_]|<[^>]+>|\[([^\]]*)\]\([^)]*\)", r"\1", title).strip().lower()
        found.add(re.sub(r"[^\w\- ]", "", plain).replace(" ", "-"))  # GitHub
        found.add(re.sub(r"[-\s]+", "-", re.sub(r"[^\w\s-]", "", plain)).strip("-"))  # MkDocs
    return found


def links(text: str) -> list[tuple[int, str]]:
    """(line, target) of every link and picture outside code: [..](x), ![..](x), [x]: y,
    <a href>, <img src>."""
    found, inside = [], fenced_lines(text)
    for i, line in enumerate(text.splitlines()):
        if i in inside:
            continue
        line = re.sub(r"`[^`]*`", "", line)
        for target in re.findall(r"\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)", line):
            found.append((i + 1, target))
        for target in re.findall(r"^\s*\[[^\]]+\]:\s*<?(\S+?)>?(?:\s|$)", line):
            found.append((i + 1, target))
        for target in re.findall(r"(?:href|src)\s*=\s*[\"']([^\"']+)[\"']", line):
            found.append((i + 1, target))
    return found


def test_the_readme_links_resolve():
    text = README.read_text(encoding="utf-8")
    broken = []
    for line, target in links(text):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):  # https:, mailto:
            continue
        path, _, anchor = target.partition("#")
        file = (README.parent / path.split("?")[0]).resolve() if path else README
        if not file.exists():
            broken.append(f"README.md:{line}: {target}: no {file}")
        elif anchor and file.suffix == ".md" and anchor not in slugs(
                file.read_text(encoding="utf-8")):
            broken.append(f"README.md:{line}: {target}: no heading #{anchor} in {path or 'it'}")
    assert not broken, "\n".join(broken)


def nav_pages() -> list[str]:
    """The .md files mkdocs.yml's nav names (read as text: no YAML library needed)."""
    text = (CHECKOUT / "mkdocs.yml").read_text(encoding="utf-8")
    nav = re.search(r"^nav:\s*\n((?:[ \t]+.*\n|\s*\n)*)", text, re.M)
    assert nav, "mkdocs.yml has no nav"
    return re.findall(r"([\w./-]+\.md)\s*$", nav.group(1), re.M)


def test_every_page_is_in_the_nav():
    named = nav_pages()
    pages = sorted(str(p.relative_to(DOCS)) for p in DOCS.glob("*.md"))
    assert not set(pages) - set(named), f"docs pages not in mkdocs.yml's nav: " \
                                        f"{sorted(set(pages) - set(named))}"
    assert not set(named) - set(pages), f"mkdocs.yml's nav names missing pages: " \
                                        f"{sorted(set(named) - set(pages))}"


# -- the command line ----------------------------------------------------------------------

def occtrack_commands(block: Block) -> list[tuple[int, list[str], bool]]:
    """(line, argv, handled) of every `occtrack ...` command in a shell block (after `$ `
    prompts, `&&`, `||`, `;`, `|`, `(`, leading VAR=value words and `time`), comments and
    redirections dropped, line continuations joined, heredoc bodies skipped, and each shell
    variable replaced by 1 (a value of any type the option takes: a number, or a path's
    part). `handled`: the command is followed by `||`, a failure the block expects."""
    commands = []
    lines = block.code.splitlines()
    heredoc = None
    joined: list[tuple[int, str]] = []
    for offset, raw in enumerate(lines, start=1):
        if heredoc is not None:
            if raw.strip() == heredoc:
                heredoc = None
            continue
        marker = re.search(r"<<-?\s*['\"]?(\w+)['\"]?", raw)
        if marker:
            heredoc = marker.group(1)
        if joined and joined[-1][1].endswith("\\"):
            joined[-1] = (joined[-1][0], joined[-1][1][:-1] + " " + raw)
        else:
            joined.append((offset, raw))
    for offset, raw in joined:
        line = raw[2:] if raw.startswith("$ ") else raw
        pieces = re.split(r"(&&|\|\||;|\||\(|\)|\$\()", line)
        for k in range(0, len(pieces), 2):
            part, handled = pieces[k], pieces[k + 1:k + 2] == ["||"]
            try:
                words = shlex.split(part, comments=True)
            except ValueError:
                continue
            while words and (re.match(r"^\w+=", words[0]) or words[0] in ("time", "exec")):
                words = words[1:]
            if words[:3] == ["python", "-m", "occtrack"]:
                words = ["occtrack", *words[3:]]
            if words and words[0] == "occtrack":  # a shell variable stands for a value
                argv = [re.sub(r"\$\{?\w+\}?", "1", w) for w in without_redirections(words[1:])]
                commands.append((block.line + offset, argv, handled))
    return commands


def without_redirections(words: list[str]) -> list[str]:
    """The words of a command without its redirections (> f, 2>&1, <f, &> f)."""
    kept, skip_next = [], False
    for word in words:
        if skip_next:
            skip_next = False
        elif re.fullmatch(r"(\d*|&)[<>]{1,2}", word):
            skip_next = True
        elif not re.fullmatch(r"(\d*|&)[<>]{1,2}\S+", word):
            kept.append(word)
    return kept


SHELL_COMMANDS = [(f"{b.page}:{line}", argv, handled) for found in ALL.values() for b in found
                  if b.shell or b.language in SHOWN_SHELL_LANGS
                  for line, argv, handled in occtrack_commands(b)]


@pytest.mark.parametrize(("where", "argv", "handled"), SHELL_COMMANDS,
                         ids=[w for w, _, _ in SHELL_COMMANDS])
def test_shell_commands_name_real_subcommands_and_options(where, argv, handled, capsys):
    """Every command parses; one the block expects to fail (`occtrack ... || ...`, a usage
    error shown on purpose) need only name a real subcommand and real options."""
    from occtrack.cli import _command_of, build_parser

    parser = build_parser(_command_of(argv))
    try:
        parser.parse_args(argv)
    except SystemExit as exit_:
        err = capsys.readouterr().err
        if handled and not re.search(r"unrecognized arguments|argument (COMMAND|TABLE|SCENE)"
                                     r": invalid choice", err):
            return
        assert exit_.code == 0, f"{where}: occtrack {' '.join(argv)}: {err.strip()}"


def subcommands(parser) -> dict[str, object]:
    import argparse

    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            unique = {}
            for name, sub in action.choices.items():
                if all(sub is not seen for seen in unique.values()):
                    unique[name] = sub
            return unique
    return {}


def option_strings(parser) -> list[str]:
    import argparse

    return [s for action in parser._actions if not isinstance(action, argparse._HelpAction)
            for s in action.option_strings]


def sections(text: str) -> list[tuple[int, list[str], str]]:
    """(level, the heading's words without a leading `occtrack`, the section's text up to
    the next heading of its level or higher) of every heading outside code."""
    lines, inside = text.splitlines(), fenced_lines(text)
    heads = []
    for i, line in enumerate(lines):
        match = re.match(r"^(#{1,6})\s+(.*)$", line)
        if match and i not in inside:
            words = re.findall(r"[\w-]+", re.sub(r"\{[^}]*\}", "", match.group(2)).lower())
            if words[:1] == ["occtrack"]:
                words = words[1:]
            heads.append((i, len(match.group(1)), words))
    found = []
    for n, (i, level, words) in enumerate(heads):
        end = next((j for j, lev, _ in heads[n + 1:] if lev <= level), len(lines))
        found.append((level, words, "\n".join(lines[i:end])))
    return found


def find_section(text: str, path: list[str], known: set[str]) -> str | None:
    """The section of docs/cli.md for a command path (["track"], ["reproduce", "table2"]):
    a heading that starts with the path (after an optional `occtrack`), not followed by one
    of the path's own subcommands; for a sub-subcommand, also a heading that starts with its
    name inside its parent's section."""
    for _, words, body in sections(text):
        if words[:len(path)] == path and (len(words) == len(path)
                                          or words[len(path)] not in known):
            return body
    if len(path) == 2:
        parent = find_section(text, path[:1], known)
        if parent is not None:
            for _, words, body in sections(parent)[1:]:
                if words[:1] == path[1:]:
                    return body
    return None


def test_the_cli_page_documents_every_command_and_option():
    from occtrack.cli import build_parser

    page = DOCS / "cli.md"
    assert page.is_file(), "docs/cli.md not found"
    text = page.read_text(encoding="utf-8")
    commands = subcommands(build_parser("*"))
    paths = []
    for name, parser in commands.items():
        paths.append(([name], parser))
        for sub_name, sub in subcommands(parser).items():
            paths.append(([name, sub_name], sub))
    known = {words[-1] for words, _ in paths}
    problems = []
    for path, parser in paths:
        where = "occtrack " + " ".join(path)
        body = find_section(text, path, known)
        if body is None:
            problems.append(f"{where}: no section (a heading `{where}`) in docs/cli.md")
            continue
        missing = [s for s in option_strings(parser)
                   if not re.search(rf"(?<![\w-]){re.escape(s)}(?![\w-])", body)]
        if missing:
            problems.append(f"{where}: its section does not name {', '.join(missing)}")
    assert not problems, "\n".join(problems)


# -- the finders themselves ------------------------------------------------------------------

def test_the_block_finder_reads_fences_and_markers():
    text = ("# t\n```python\nx = 1\n```\n<!-- docs-test: skip needs a camera -->\n"
            "```python\nimport cv2\n```\n```bash\n$ occtrack demo --seed 1 && ls\n```\n"
            "<!-- docs-test: output ignore=\\d+ s -->\n```text\ndone in 3 s\n```\n"
            "1. a list\n\n    ```sh title=\"x\"\n    occtrack track a \\\n      -o b\n    ```\n")
    found = blocks(text)
    assert [(b.language, b.line, b.mark, b.mark_arg) for b in found] == [
        ("python", 2, None, ""), ("python", 6, "skip", "needs a camera"),
        ("bash", 9, None, ""), ("text", 13, "output", "ignore=\\d+ s"),
        ("sh", 18, None, "")]
    assert found[4].code == "occtrack track a \\\n  -o b\n"
    assert occtrack_commands(found[2]) == [(10, ["demo", "--seed", "1"], False)]
    assert occtrack_commands(found[4]) == [(19, ["track", "a", "-o", "b"], False)]
    here = Block("p.md", "bash", 1, "cat > a.toml <<'EOF'\nocctrack = 1\nEOF\n"
                 "X=1 occtrack eval $OUT --gt \"${GT}\" 2>&1 >out.txt | tail -1\n"
                 "occtrack track --fps 0 2>&1 || echo $?\n")
    assert occtrack_commands(here) == [(5, ["eval", "1", "--gt", "1"], False),
                                       (6, ["track", "--fps", "0"], True)]
    assert normalise("\n a 12 s  \n\n", r"\d+ s") == [" a <ignored>"]


def test_the_cli_sections_are_found():
    text = ("# CLI\n## `occtrack track`: boxes\n--force\n## occtrack reproduce\n-h\n"
            "### table2\n--quick\n## occtrack reproduce table3\n--seed\n```sh\n# track\n```\n")
    known = {"track", "reproduce", "table2", "table3"}
    assert find_section(text, ["track"], known).splitlines()[1] == "--force"
    assert "--quick" in find_section(text, ["reproduce"], known)
    assert find_section(text, ["reproduce", "table2"], known).endswith("--quick")
    assert "--seed" in find_section(text, ["reproduce", "table3"], known)
    assert find_section(text, ["eval"], known) is None
    assert {"occtrack-track-boxes", "cli"} <= slugs(text)


if __name__ == "__main__":  # the blocks of every page: python tests/test_docs.py
    def tally(found: list[Block]) -> dict[str, int]:
        counts = dict.fromkeys(("python", "shell", "run", "slow", "skip", "data", "transcripts"),
                               0)
        for b in found:
            if b.runnable:
                counts["python" if b.python else "shell"] += 1
                counts[b.mark if b.mark in ("slow", "skip") else "run"] += 1
                counts["data"] += b.uses_data and b.mark != "skip"
            elif b.mark == "output":
                counts["transcripts"] += 1
        return counts

    print("page: python / shell blocks; of them run in the suite / slow (OCCTRACK_DOCS_SLOW=1)"
          " / skip; naming the data; transcripts compared")
    for path, found in [*ALL.items(), (None, [b for f in ALL.values() for b in f])]:
        c = tally(found)
        name = path.relative_to(CHECKOUT) if path else "total"
        print(f"{name}: python {c['python']}, shell {c['shell']}; run {c['run']}, "
              f"slow {c['slow']}, skip {c['skip']}; data {c['data']}; "
              f"transcripts {c['transcripts']}")
