"""The C++ example (`examples/cpp/krang_example.cpp`, linked with Krang's C library `c/krang`)
prints M, g and τ equal to the Rust results for its state. `$KANEGEN_CPP_EXAMPLE` names the
compiled example (`.ci/run` builds it); without it the test is skipped."""

import os
import subprocess

import pytest

from conftest import close


def parse(text):
    """The matrices the example prints: name → list of numbers."""
    blocks, name = {}, None
    for line in text.splitlines():
        if line.endswith(" ="):
            name = line[:-2]
            blocks[name] = []
        elif name is not None and line.startswith("  "):
            blocks[name].extend(float(x) for x in line.split())
    return blocks


def test_cpp_example_prints_the_rust_results(reference):
    exe = os.environ.get("KANEGEN_CPP_EXAMPLE")
    if not exe:
        pytest.skip("KANEGEN_CPP_EXAMPLE is not set")
    out = subprocess.run([exe], check=True, capture_output=True, text=True).stdout
    printed = parse(out)
    expected = reference["krang"]["example_state"]
    assert set(printed) == {"M", "g", "tau"}
    for name in ("M", "g", "tau"):
        assert close(printed[name], expected[name]), name
