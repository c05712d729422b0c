"""lucent from Python: render translucent objects, solve frame sessions, make materials.

The compiled module ``lucent._lucent`` goes through lucent's own library: the same scene
resolution, frame session and GPU raster as the ``lucent`` command line, so
``lucent.render(...)`` is the image ``lucent render --out x.exr`` writes.

    import lucent
    img = lucent.render("bunny.obj", material="marble", scale=0.05, width=256, height=256)
    img.shape  # (256, 256, 4) float32: linear radiance premultiplied by coverage, coverage

    s = lucent.Session(vertices=v, faces=f, material=lucent.Material.preset("skin1"))
    s.solve().face_b  # radiosity per face
    s.deform("twist:30")
    s.solve()         # links updated incrementally (Mertens 2003 section 5.5)

Errors are ``lucent.LucentError`` with lucent's one-line message.
"""

from ._lucent import LucentError, Material, Session, Solution, presets, read_exr, render, write_exr

__all__ = ["LucentError", "Material", "Session", "Solution", "presets", "read_exr", "render", "write_exr"]
