"""lucent from Python: materials, a session on a numpy mesh against the exact solve and against
the same mesh read from a file, a deformation against a fresh solve of the deformed mesh, the
errors, the GIL, and agreement with the command line's EXR."""

import os
import subprocess
import threading

import numpy as np
import pytest

import lucent
from conftest import ROOT, icosphere, write_obj

LIGHT = ["dir:-0.5,-0.7,-0.5"]


def rel(a, b):
    """Mean of |a - b| over the mean of |b|, over all channels."""
    return float(np.abs(a - b).mean() / np.abs(b).mean())


def test_materials_presets_coefficients_and_colour_round_trip():
    marble = lucent.Material.preset("Marble")
    assert marble.sigma_s_prime == [2.19, 2.62, 3.0] and marble.eta == 1.3
    assert "wax" in lucent.presets() and "skimmilk" in lucent.presets()
    m = lucent.Material([1.0, 2.0, 3.0], [0.01, 0.02, 0.03], eta=1.4, name="mine")
    assert (m.sigma_a, m.eta, m.name) == ([0.01, 0.02, 0.03], 1.4, "mine")
    # albedo + mean free path -> coefficients -> albedo + mean free path.
    albedo, mfp = [0.9, 0.6, 0.3], [2.0, 1.0, 0.5]
    c = lucent.Material.from_albedo_mfp(albedo, mfp, eta=1.3)
    a2, m2 = c.albedo_mfp()
    np.testing.assert_allclose(a2, albedo, rtol=1e-6)
    np.testing.assert_allclose(m2, mfp, rtol=1e-12)
    np.testing.assert_allclose(1 / (np.add(c.sigma_s_prime, c.sigma_a)), mfp, rtol=1e-12)


def test_bad_input_raises_lucent_error_with_one_line():
    cases = [
        (lambda: lucent.Material.preset("plutonium"), "unknown material 'plutonium'"),
        (lambda: lucent.Material([1, 1, 1], [0, 0.1, 0.1]), "sigma_a"),
        (lambda: lucent.Material.from_albedo_mfp([1.5, 0.5, 0.5], [1, 1, 1]), "albedo 1.5"),
        (lambda: lucent.Session(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], faces=[[0, 1, 7]]), "index 7"),
        (lambda: lucent.Session("no/such/mesh.obj"), "no/such/mesh.obj"),
        (lambda: lucent.Session(scale=-1.0), "0.0001..=100"),
        (lambda: lucent.Session(method="htsm"), "htsm"),
        (lambda: lucent.Session(profile="gaussian"), "gaussian"),
        (lambda: lucent.Session(lights=["spot:1,2"]), "spot:1,2"),
        (lambda: lucent.Session(deform="twist:abc"), "twist:abc"),
        (lambda: lucent.render(width=0), "width"),
        (lambda: lucent.read_exr("no/such.exr"), "no/such.exr"),
    ]
    for call, needle in cases:
        with pytest.raises(lucent.LucentError) as e:
            call()
        message = str(e.value)
        assert needle in message and "\n" not in message, message
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        lucent.Session(vertices=np.zeros((4, 2)), faces=[[0, 1, 2]])
    with pytest.raises(TypeError):
        lucent.Session(material=3)
    v, f = icosphere(1)
    s = lucent.Session(vertices=v, faces=f, refine=0, bounces=0)
    with pytest.raises(lucent.LucentError, match="42 vertices"):
        s.set_pose(np.zeros((5, 3)))
    with pytest.raises(lucent.LucentError, match="not finite"):
        s.set_pose(np.full((42, 3), np.nan))


def session(v, f, **kw):
    args = dict(vertices=v, faces=f, material="marble", scale=0.02, lights=LIGHT, refine=0, width=64, height=48)
    args.update(kw)
    return lucent.Session(**args)


def test_numpy_mesh_solves_as_its_file_and_near_the_exact_solve(tmp_path):
    v, f = icosphere(3)
    hier = session(v, f).solve()
    assert hier.face_b.shape == (len(f), 3) and hier.vertex_radiance.shape == (len(v), 3)
    assert hier.face_b.dtype == np.float32 and np.isfinite(hier.face_b).all()
    assert (hier.face_b >= 0).all() and hier.face_b.max() > 0
    assert hier.links > 0 and hier.fresh and hier.timings["total_ms"] > 0
    # The same mesh from a file: the same scene resolution, the same numbers.
    obj = tmp_path / "sphere.obj"
    write_obj(obj, v, f)
    from_file = lucent.Session(str(obj), material="marble", scale=0.02, lights=LIGHT, refine=0, width=64, height=48)
    np.testing.assert_array_equal(from_file.solve().face_b, hier.face_b)
    # The hierarchical solve against the exact O(N^2) one (the project's reference solver).
    exact = session(v, f, method="exact").solve()
    assert exact.links is None
    assert rel(hier.face_b, exact.face_b) < 0.02, rel(hier.face_b, exact.face_b)


def test_deformation_updates_like_a_fresh_solve_of_the_deformed_mesh():
    v, f = icosphere(3)
    s = session(v, f)
    assert s.mode == "incremental"
    rest = s.solve()
    again = s.solve()
    assert not again.fresh and again.timings["total_ms"] == 0
    s.deform("twist:40")
    bent = s.solve()
    assert bent.fresh and not np.allclose(s.vertices, s.rest_vertices)
    # A session made on the deformed mesh from scratch, solved on the fly.
    fresh = session(v, f, deform="twist:40", mode="on-the-fly")
    np.testing.assert_allclose(fresh.vertices, s.vertices, rtol=0, atol=1e-6)
    ref = fresh.solve()
    assert rel(bent.face_b, ref.face_b) < 0.02, rel(bent.face_b, ref.face_b)
    assert rel(bent.face_b, rest.face_b) > 10 * rel(bent.face_b, ref.face_b), "the twist changed nothing"
    # Back to the rest pose through set_pose: the rest result again.
    s.set_pose(s.rest_vertices)
    back = s.solve()
    assert rel(back.face_b, rest.face_b) < 0.02
    # A new material and new lights re-solve.
    s.set_material(lucent.Material.preset("ketchup"))
    s.set_lights(["dir:0.5,-0.7,-0.5"])
    ketchup = s.solve()
    assert ketchup.fresh and s.material.name == "Ketchup"
    assert ketchup.face_b[:, 0].mean() > 3 * ketchup.face_b[:, 2].mean(), "ketchup is red"


def test_solve_releases_the_gil():
    v, f = icosphere(3)
    s = session(v, f, method="exact", bounces=0)
    started, done = threading.Event(), []
    t = threading.Thread(target=lambda: (started.set(), done.append(s.solve())))
    t.start()
    started.wait()
    ticks = 0
    while t.is_alive():
        ticks += 1
    t.join()
    # Held, this thread could not run at all until the solve returned.
    assert done and ticks > 1000, ticks


def test_render_equals_the_command_lines_exr(gpu, lucent_bin, tmp_path):
    scene = os.path.join(ROOT, "validation", "scenes", "sphere_marble_2cm.toml")
    out = tmp_path / "cli.exr"
    cmd = [lucent_bin, "render", "--scene", scene, "--width", "96", "--height", "72", "--no-surface", "--out", str(out)]
    subprocess.run(cmd, check=True, capture_output=True)
    cli = lucent.read_exr(out)
    ours = lucent.render(scene=scene, width=96, height=72, surface=False)
    assert ours.shape == (72, 96, 4) and ours.dtype == np.float32
    assert ours[..., 3].max() == 1.0 and ours[..., 3].min() == 0.0, "coverage in alpha"
    peak = float(np.abs(cli).max())
    assert peak > 0
    err = np.abs(ours - cli) / np.maximum(np.abs(cli), 1e-3 * peak)
    assert float(err.max()) <= 1e-5, float(err.max())
    # The EXR round trip of the module itself.
    back = tmp_path / "ours.exr"
    lucent.write_exr(back, ours)
    np.testing.assert_array_equal(lucent.read_exr(back), ours)


def test_numpy_mesh_renders_as_its_file_and_session_renders_its_solve(gpu, tmp_path):
    v, f = icosphere(2)
    obj = tmp_path / "ball.obj"
    write_obj(obj, v, f)
    kw = dict(material="skin1", scale=0.03, lights=LIGHT, width=48, height=40)
    from_arrays = lucent.render(vertices=v, faces=f, **kw)
    np.testing.assert_array_equal(from_arrays, lucent.render(str(obj), **kw))
    # As `lucent render` solves one image with bounces: render mode.
    s = lucent.Session(vertices=v, faces=f, mode="render", **kw)
    np.testing.assert_array_equal(s.render(), from_arrays)
