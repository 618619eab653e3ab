"""The documentation runs: docs/python.md's install command and every `python` block of it
(and the README's Python command), each on this build; where a page shows what a snippet
prints (a `text` block right after it), the printed lines are those."""

import contextlib
import io
import re
import subprocess
import sys

from conftest import ROOT

BLOCK = re.compile(r"```(\w+)\n(.*?)```", re.S)


def blocks(page):
    """(language, text) of each fenced block of `page`, in order."""
    return [(m.group(1), m.group(2)) for m in BLOCK.finditer((ROOT / page).read_text())]


def shown_after(bs, i):
    """The lines of the `text` block right after block i, if there is one."""
    if i + 1 < len(bs) and bs[i + 1][0] == "text":
        return bs[i + 1][1].splitlines()
    return None


def python_command(line):
    """The code of a `target/pyenv/bin/python -c "..."` line."""
    m = re.search(r'target/pyenv/bin/python -c "(.*)"', line)
    assert m, line
    return m.group(1)


def test_the_install_command_prints_what_python_md_shows():
    bs = blocks("docs/python.md")
    i = next(i for i, (lang, text) in enumerate(bs) if lang == "sh" and "pyenv/bin/python -c" in text)
    out = subprocess.run([sys.executable, "-c", python_command(bs[i][1])], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == shown_after(bs, i)
    # the README's table names the same command
    readme = (ROOT / "README.md").read_text()
    line = next(l for l in readme.splitlines() if "pyenv/bin/python -c" in l)
    assert python_command(line.split("`")[1]) == python_command(bs[i][1])


def test_every_python_block_of_python_md_runs(sim_program, monkeypatch):
    monkeypatch.setenv("SOFTFINGER_SIM", str(sim_program))
    bs = blocks("docs/python.md")
    ran = 0
    ns = {}  # one session for the page, as a reader runs its blocks
    for i, (lang, text) in enumerate(bs):
        if lang != "python":
            continue
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(text, f"docs/python.md block {i}", "exec"), ns)
        shown = shown_after(bs, i)
        if shown is not None:
            assert out.getvalue().splitlines() == shown, text
        ran += 1
    assert ran >= 2


def test_every_table_of_the_docs_has_its_header_row():
    """A Markdown table renders only under its header and delimiter rows: a block of `| ... |`
    lines (outside code blocks) whose second line is no `| --- |` row shows as plain text
    (docs/reliability.md's table of finds, split by a blank line, did)."""
    pages = sorted(ROOT.glob("docs/**/*.md")) + [ROOT / "README.md"] + sorted(ROOT.glob("*/README.md"))
    bad = []
    for page in pages:
        lines = page.read_text().splitlines()
        fence, i = False, 0
        row = lambda s: s.startswith("|") and s.rstrip().endswith("|")
        while i < len(lines):
            if lines[i].lstrip().startswith("```"):
                fence, i = not fence, i + 1
                continue
            if not fence and row(lines[i]):
                j = i
                while j < len(lines) and row(lines[j]):
                    j += 1
                if j - i < 2 or not re.match(r"^\|\s*:?-{3,}", lines[i + 1]):
                    bad.append(f"{page.relative_to(ROOT)}:{i + 1}: {lines[i][:60]}")
                i = j
                continue
            i += 1
    assert not bad, "tables without a header row:\n" + "\n".join(bad)
