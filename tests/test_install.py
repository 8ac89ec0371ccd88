"""The README's install, as a newcomer follows it: a clone folder named ``floewave`` beside
the user's script does not shadow the installed package (issue [harden] 7: with the
editable install the README gave, ``from floewave import ModelConfig`` there failed with
``ImportError: ... (unknown location)``: the clone folder was taken for a namespace package
before the editable finder was asked).

The tracked files are copied into ``<tmp>/floewave`` (a clone's default name), the README's
``## Install`` command is run there in a fresh virtual environment that sees this one's
packages (``--system-site-packages``: nothing is downloaded but the build backend), and a
script in ``<tmp>`` imports floewave and sweep.
"""
from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = ("from floewave import ModelConfig, run_point\nimport sweep, floewave\n"
          "print(floewave.__file__)\n")


def readme_install_command() -> list[str]:
    """The first command of the README's ``## Install`` section's code block."""
    text = (ROOT / "README.md").read_text()
    section = text.split("## Install", 1)[1].split("\n## ", 1)[0]
    block = re.search(r"```bash\n(.*?)```", section, re.S).group(1)
    line = next(x for x in block.splitlines() if x.strip().startswith("pip install"))
    return shlex.split(line.split("#", 1)[0])


def test_readme_install_command_is_a_plain_install():
    """Fast: the README's install is not an editable one (``-e`` is what shadows)."""
    cmd = readme_install_command()
    assert cmd[:2] == ["pip", "install"]
    assert "-e" not in cmd and "--editable" not in cmd, cmd


@pytest.mark.slow  # fast: test_readme_install_command_is_a_plain_install
def test_a_clone_folder_beside_a_script_does_not_shadow_the_install(tmp_path):
    clone = tmp_path / "floewave"
    files = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True,
                           check=True).stdout.decode().split("\0")
    for name in filter(None, files):
        src = ROOT / name
        if src.is_file() and not name.startswith(("results/", "docs/atlas/")):
            (clone / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, clone / name)
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)],
                   check=True)
    env = dict(os.environ, PATH=f"{venv / 'bin'}{os.pathsep}{os.environ['PATH']}",
               VIRTUAL_ENV=str(venv), PIP_DISABLE_PIP_VERSION_CHECK="1")
    env.pop("PYTHONPATH", None)
    cmd = readme_install_command()
    got = subprocess.run([str(venv / "bin" / "python"), "-m", *cmd[:1], *cmd[1:],
                          "--quiet"], cwd=clone, env=env, capture_output=True, text=True,
                         timeout=600)
    assert got.returncode == 0, got.stderr[-2000:]
    (tmp_path / "s.py").write_text(SCRIPT)
    run = subprocess.run([str(venv / "bin" / "python"), "s.py"], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    assert str(venv) in run.stdout, run.stdout  # the installed copy, not the clone's


def test_one_version_everywhere():
    """The release's version is the same in pyproject.toml, ``floewave.__version__`` and
    CITATION.cff, and docs/changelog.md has an entry for it (a release tags all four)."""
    import tomllib

    import floewave

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    cff = re.search(r"^version:\s*(\S+)", (ROOT / "CITATION.cff").read_text(), re.M).group(1)
    assert project == floewave.__version__ == cff.strip("\"'"), (project, floewave.__version__,
                                                                 cff)
    changelog = (ROOT / "docs" / "changelog.md").read_text()
    assert re.search(rf"^## Release {re.escape(project)}\b", changelog, re.M), project
