"""The Python blocks of the user guide (docs/guide.md), of the own-platform tutorial (docs/platforms.md) and of the
README's "Your first hour" run as written.

Each document's blocks run in order in one fresh interpreter (as a reader pastes them into one
session), headless (MPLBACKEND=Agg), in a temporary folder that sees the repository's examples/
(docs/platforms.md loads examples/my_platform/ as a reader in the repository root would).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def first_hour(readme: str) -> str:
    start = readme.index("## Your first hour")
    end = readme.find("\n## ", start + 5)
    return readme[start:end if end > 0 else None]


@pytest.mark.parametrize("doc", ["docs/guide.md", "docs/platforms.md", "README.md"])
def test_blocks_run(doc, tmp_path):
    text = (ROOT / doc).read_text()
    if doc == "README.md":
        text = first_hour(text)
    blocks = python_blocks(text)
    assert len(blocks) >= 3, doc
    (tmp_path / "examples").symlink_to(ROOT / "examples", target_is_directory=True)
    script = tmp_path / "blocks.py"
    script.write_text("\n\n".join(blocks))
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"{doc}:\n{proc.stdout[-2000:]}\n{proc.stderr[-3000:]}"
    assert "Warning" not in proc.stderr, proc.stderr


def test_guide_links_exist():
    text = (ROOT / "docs" / "guide.md").read_text()
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        assert (ROOT / "docs" / target).exists(), target
    for script in re.findall(r"`(examples/[a-z_]+\.py)`", text):
        assert (ROOT / script).is_file(), script
