"""Every example script and tutorial notebook runs in smoke mode, so none of them rots."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py"))


def _env() -> dict[str, str]:
    env = dict(os.environ, RADIOMETRIA_SMOKE="1", MPLBACKEND="Agg", JAX_PLATFORMS="cpu")
    env.pop("XLA_FLAGS", None)
    return env


@pytest.mark.slow
@pytest.mark.parametrize("script", EXAMPLES, ids=lambda p: p.stem)
def test_example_runs_in_smoke_mode(script, tmp_path):
    proc = subprocess.run(
        [sys.executable, str(script), str(tmp_path)],
        env=_env(),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]


def test_notebooks_are_paired_and_stripped():
    jupytext = pytest.importorskip("jupytext")
    for py in NOTEBOOKS:
        ipynb = py.with_suffix(".ipynb")
        assert ipynb.exists(), f"{ipynb.name} is missing: run `jupytext --sync {py.name}`"
        nb = json.loads(ipynb.read_text())
        for cell in nb["cells"]:
            assert not cell.get("outputs"), f"{ipynb.name} has outputs: strip them"
        src_py = [c["source"] for c in jupytext.read(py).cells]
        src_nb = [c["source"] for c in jupytext.read(ipynb).cells]
        assert src_py == src_nb, f"{ipynb.name} and {py.name} differ: run `jupytext --sync`"


@pytest.mark.slow
@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_executes_in_smoke_mode(notebook, tmp_path, monkeypatch):
    jupytext = pytest.importorskip("jupytext")
    nbclient = pytest.importorskip("nbclient")
    for key, value in _env().items():
        monkeypatch.setenv(key, value)
    monkeypatch.delenv("XLA_FLAGS", raising=False)
    nb = jupytext.read(notebook)
    client = nbclient.NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()
