"""The README's first two commands and `.ci/run` stay in step (CI proves the README)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _readme_commands() -> list[str]:
    block = re.search(r"```sh\n(.*?)```", (ROOT / "README.md").read_text(), re.S).group(1)
    return [line for line in block.splitlines() if line.strip()]


def test_readme_opens_with_the_two_commands():
    run_line, test_line = _readme_commands()[:2]
    assert "pip install ." in run_line and "lagcomp run double_pendulum" in run_line
    assert "pip install '.[test]'" in test_line and test_line.endswith("python -m pytest")


def test_ci_runs_the_readme_test_command():
    ci = (ROOT / ".ci" / "run").read_text()
    _, test_line = _readme_commands()[:2]
    assert "pip install --quiet '.[test]'" in ci
    assert "\npython -m pytest\n" in ci
    assert test_line.split("&& ")[-1] == "python -m pytest"
    run_line = _readme_commands()[0]
    assert run_line.split("&& ")[-1] in ci  # the main job runs in CI too


def test_readme_quick_start_runs_as_written(monkeypatch, cache_dir):
    monkeypatch.setenv("LAGCOMP_CACHE_DIR", str(cache_dir))
    block = re.search(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S).group(1)
    namespace: dict = {}
    exec(compile(block, "README.md", "exec"), namespace)
    sol = namespace["sol"]
    assert sol.success and sol.t[-1] == 100 and sol.q.shape == (len(sol.t), 2)
    assert sol.energy_drift() < 2e-7  # measured 6.3e-8 (dop853 at rtol 1e-10 over 100 s)
