"""What the lucent module's tests share: a closed numpy mesh, the repository's paths, and the
project's rule for what a machine lacks (a GPU adapter, the `lucent` binary): the test says
SKIPPED with the way to get it on a developer's machine, and fails under CI (`CI` set)."""

import os

import numpy as np
import pytest

import lucent

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


def need(what, how):
    """Skips (fails under CI) for a missing piece of the machine."""
    message = f"{what} ({how})"
    if os.environ.get("CI"):
        pytest.fail(f"CI has everything installed, but: {message}")
    pytest.skip(message)


def icosphere(levels):
    """A unit icosphere: the icosahedron's faces split in four `levels` times, vertices pushed
    to the sphere. Closed, counter-clockwise seen from outside."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
         (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [np.array(p, dtype=np.float64) / np.linalg.norm(p) for p in v]
    for _ in range(levels):
        mid, nf = {}, []

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = v[a] + v[b]
                v.append(p / np.linalg.norm(p))
                mid[key] = len(v) - 1
            return mid[key]

        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return np.array(v, dtype=np.float32), np.array(f, dtype=np.int64)


def write_obj(path, v, f):
    with open(path, "w") as out:
        for p in v:
            out.write(f"v {float(p[0])!r} {float(p[1])!r} {float(p[2])!r}\n")
        for a, b, c in f:
            out.write(f"f {a + 1} {b + 1} {c + 1}\n")


@pytest.fixture(scope="session")
def gpu():
    """A GPU adapter (Mesa's llvmpipe or lavapipe will do), or a skip."""
    try:
        lucent.render(width=8, height=8, refine=0, bounces=0, single_scattering="off")
    except lucent.LucentError as e:
        if "adapter" in str(e).lower() or "gpu" in str(e).lower():
            need(f"no GPU adapter: {e}", "apt-get install mesa-vulkan-drivers libegl1 libgl1-mesa-dri")
        raise


@pytest.fixture(scope="session")
def lucent_bin():
    """The `lucent` binary of this checkout (`LUCENT_BIN`, else target/release/lucent)."""
    path = os.environ.get("LUCENT_BIN", os.path.join(ROOT, "target", "release", "lucent"))
    if not os.path.isfile(path):
        need(f"no lucent binary at {path}", "cargo build --release")
    return path
