"""The worked example runs and writes its plot (matplotlib, Agg backend), with a timeout."""

import subprocess
import sys

from conftest import ROOT


def test_the_before_after_example_writes_its_figure(tmp_path):
    out = tmp_path / "before_after.png"
    script = ROOT / "python" / "examples" / "before_after.py"
    p = subprocess.run([sys.executable, str(script), str(out)], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "diagnosis:" in p.stdout
