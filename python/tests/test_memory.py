"""An output sized by the input that does not fit in memory raises MemoryError, and the
interpreter goes on: never an abort (SIGABRT) that takes it down.

Each call runs in a child interpreter under an address-space limit (RLIMIT_AS, at most 4 GB):
the limit is the address space the child uses once the package is loaded and warmed up (rayon's
threads started) plus a headroom smaller than what the call must allocate, so the allocation
fails wherever the machine's memory is. The child then makes a small call of the same function
and compares it with the value it had before the limit.
"""

import os
import signal
import subprocess
import sys
import textwrap

import pytest

PANDA = "[0.5, 0.0, 0.0, 0.1, 1e-3, 1e-3, 1e-3]"

CHILD = """
import resource

import numpy as np

import toolconf


def address_space():
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024


{setup}
before = small()
limit = min(4 << 30, address_space() + {headroom})
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
try:
    big()
except MemoryError as e:
    print("MemoryError:", e)
else:
    print("a result")
assert np.array_equal(small(), before)
print("small call after it: the same")
"""

CASES = {
    # 10⁶ Panda tools are 56 MB of parameters and 3 GB of matrices (A alone is 1.6 GB).
    "confidence": (f"""
tool = np.array({PANDA})
def small():
    return toolconf.confidence("panda", np.tile(tool, (2048, 1)), "velocity")["logdet"]
tools = np.tile(tool, (10**6, 1))
def big():
    toolconf.confidence("panda", tools, "velocity")
""", 500 << 20, "confidence of 1000000 panda tools: cannot allocate"),
    # One shared tool and state, 4·10⁶ controls (224 MB): the copy of the controls does not fit
    # in half of their size.
    "dynamics": (f"""
tool, state = np.array({PANDA}), np.linspace(-0.5, 0.5, 14)
def small():
    return toolconf.dynamics("panda", tool, state, np.zeros((4096, 7)))
controls = np.zeros((4 * 10**6, 7))
def big():
    toolconf.dynamics("panda", tool, state, controls)
""", 112 << 20, "control: a float64 array of shape [4000000, 7]: cannot allocate"),
    # 10⁵ tools × 10³ perturbations are 10⁸ episodes: their rows (10 GB) are allocated, and
    # refused, before any episode runs.
    "simulate_batch": ("""
tools = np.tile([0.3, 0.4, 0.5, 0.2], (10**5, 1))
def small():
    return toolconf.simulate_batch("arm2", tools[:4], "position", [0.0, 0.1], t_end=0.2)["cost_j"]
def big():
    toolconf.simulate_batch("arm2", tools, "position", np.linspace(-1, 1, 1000), t_end=0.2)
""", 500 << 20, "simulate_batch of 100000 tools × 1000 perturbations: cannot allocate"),
}


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS and /proc are Linux's")
@pytest.mark.parametrize("name", sorted(CASES))
def test_an_output_that_does_not_fit_is_memory_error(name):
    setup, headroom, message = CASES[name]
    script = textwrap.dedent(CHILD).format(setup=setup, headroom=headroom)
    child = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                           timeout=300, env={**os.environ, "RAYON_NUM_THREADS": "2"})
    assert child.returncode != -signal.SIGABRT, child.stderr
    assert child.returncode == 0, child.stderr
    lines = child.stdout.splitlines()
    assert lines[0].startswith("MemoryError: " + message), child.stdout
    assert lines[1] == "small call after it: the same"
