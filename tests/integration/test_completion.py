"""Shell completion (issue 26 item 4): ``feeddrive --install-completion`` installs typer's
completion script for the user's shell, and the installed script completes commands."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

EXE = Path(sys.executable).with_name("feeddrive")

pytestmark = pytest.mark.skipif(shutil.which("bash") is None or not EXE.exists(),
                                reason="needs bash and the installed feeddrive script")


def _env(home: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("_TYPER")}
    env.update(HOME=str(home), SHELL="/bin/bash")
    return env


def test_install_completion_bash_completes_commands(tmp_path: Path) -> None:
    # run from bash, as a user types it: typer detects the shell from the parent process
    installed = subprocess.run(["bash", "-c", f"'{EXE}' --install-completion"],
                               env=_env(tmp_path), capture_output=True, text=True, timeout=60)
    assert installed.returncode == 0, installed.stderr
    script = tmp_path / ".bash_completions" / "feeddrive.sh"
    assert script.is_file(), installed.stdout
    assert f"source '{script}'" in (tmp_path / ".bashrc").read_text(encoding="utf-8")
    # the installed script, sourced, completes 'feeddrive sim' to the simulate command and
    # 'feeddrive identify ' to its subcommands
    probe = (f"source '{script}'; "
             "COMP_WORDS=(feeddrive sim); COMP_CWORD=1; _feeddrive_completion "
             f"'{EXE}'; printf '%s\\n' \"${{COMPREPLY[@]}}\"; echo ---; "
             "COMP_WORDS=(feeddrive identify ''); COMP_CWORD=2; _feeddrive_completion "
             f"'{EXE}'; printf '%s\\n' \"${{COMPREPLY[@]}}\"")
    done = subprocess.run(["bash", "-c", probe], env=_env(tmp_path), capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    first, second = done.stdout.split("---")
    assert first.split() == ["simulate"]
    assert {"static", "dynamic"} <= set(second.split())


def test_show_completion_prints_the_script(tmp_path: Path) -> None:
    shown = subprocess.run(["bash", "-c", f"'{EXE}' --show-completion"], env=_env(tmp_path),
                           capture_output=True, text=True, timeout=60)
    assert shown.returncode == 0, shown.stderr
    assert "complete -o default -F _feeddrive_completion feeddrive" in shown.stdout
