"""The shipped EfficientNet-Lite0 weights are found without importing torch."""

from __future__ import annotations

import subprocess
import sys

from curate.lite0_weights import lite0_weights_path


def test_weights_ship_with_the_package() -> None:
    assert lite0_weights_path().stat().st_size > 10_000_000 and lite0_weights_path().suffix == ".pth"


def test_finding_them_imports_no_torch() -> None:
    code = "import sys; from curate.lite0_weights import lite0_weights_path; lite0_weights_path(); print('torch' in sys.modules)"
    assert (
        subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
        == "False"
    )
