"""Every ``feeddrive COMMAND … --option`` written in the README, the docs pages and the
package's docstrings names an option that command takes (brief: help text and docs are
tested against the code they describe).  An outside check found ``feeddrive simulate --out``
in docs/explore.md and the explorer's docstrings (2026-12-07: the option is ``--output``;
typed, it fails with "No such option")."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
import typer.main

from feeddrive.cli import app

ROOT = Path(__file__).resolve().parents[2]
FILES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")),
         *sorted((ROOT / "src" / "feeddrive").rglob("*.py"))]
COMMAND = re.compile(r"(?<![\w./-])feeddrive ([a-z][a-z-]*)(?: ([a-z][a-z-]*))?([^;`]*)")


@pytest.fixture(scope="module")
def root() -> Any:
    """The command tree of ``feeddrive`` (built once: ~0.1 s)."""
    return typer.main.get_command(app)


def options(command: Any) -> set[str]:
    """The long options ``command`` takes."""
    return {"--help"} | {o for p in command.params for o in (*p.opts, *p.secondary_opts)
                         if o.startswith("--")}


def written(text: str) -> list[str]:
    """The code spans and the lines of fenced blocks of ``text`` that hold a command."""
    chunks = re.findall(r"`([^`\n]*feeddrive [^`\n]*)`", text)
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S):
        chunks += [line for line in block.splitlines() if "feeddrive " in line]
    return chunks


def commands_written(text: str, root: Any) -> list[tuple[str, str, set[str]]]:
    """(command as written, its options written, the options it takes) per command."""
    found = []
    for chunk in written(text):
        for m in COMMAND.finditer(chunk):
            command = root.commands.get(m.group(1))
            if command is None:
                continue
            name, rest = m.group(1), (m.group(2) or "") + (m.group(3) or "")
            if hasattr(command, "commands"):  # a group (typer may vendor click)
                sub = command.commands.get(m.group(2) or "")
                if sub is None:
                    continue
                command, name, rest = sub, f"{name} {m.group(2)}", m.group(3) or ""
            rest = rest.split("feeddrive ")[0]
            found.append((name, set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", rest)),
                          options(command)))
    return found


def test_the_scan_sees_a_wrong_option(root: Any) -> None:
    seen = commands_written("as `feeddrive simulate --out run.csv` writes", root)
    assert seen and seen[0][0] == "simulate" and "--out" not in seen[0][2]
    assert commands_written("```bash\nfeeddrive identify merge a.toml --out b.toml\n```",
                            root)[0][1] == {"--out"}


@pytest.mark.parametrize("path", FILES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_option_written_beside_a_command_exists(path: Path, root: Any) -> None:
    wrong = [(name, sorted(given - takes))
             for name, given, takes in commands_written(path.read_text(encoding="utf-8"), root)
             if given - takes]
    assert not wrong, wrong
