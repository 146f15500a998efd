"""Device strings: the syntax shared by training, scoring and embedding, and the onnxruntime providers they give."""

from __future__ import annotations

import pytest

from ground.run.device import DeviceError, onnx_providers, parse_device


@pytest.mark.parametrize(
    ("spec", "parsed"),
    [("auto", ("auto", None)), ("cpu", ("cpu", None)), ("cuda", ("cuda", None)), ("CUDA:1", ("cuda", 1))],
)
def test_parse(spec: str, parsed: tuple) -> None:
    assert parse_device(spec) == parsed


@pytest.mark.parametrize("spec", ["gpu", "cpu:0", "cuda:x", "", "mps", "cuda:-1"])
def test_bad_strings_are_named(spec: str) -> None:
    with pytest.raises(DeviceError, match="expected auto | cpu | cuda | cuda:N"):
        parse_device(spec)


def test_onnx_providers_fall_back_to_the_cpu_with_a_notice() -> None:
    gpu = ["CUDAExecutionProvider", "CPUExecutionProvider"]
    assert onnx_providers("cpu", gpu) == (["CPUExecutionProvider"], None)
    assert onnx_providers("cuda:1", gpu) == (
        [("CUDAExecutionProvider", {"device_id": 1}), "CPUExecutionProvider"],
        None,
    )
    assert onnx_providers("auto", gpu)[0][0] == ("CUDAExecutionProvider", {"device_id": 0})
    assert onnx_providers("auto", ["CPUExecutionProvider"]) == (["CPUExecutionProvider"], None)
    providers, notice = onnx_providers("cuda", ["CPUExecutionProvider"])
    assert providers == ["CPUExecutionProvider"] and "no CUDA provider" in notice and "\n" not in notice
