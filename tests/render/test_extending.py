"""`docs/extending.md` runs as written: its worked example adds a BSDF in user code."""

import re
from pathlib import Path

import jax.numpy as jnp
import numpy as np

import radiometria.render as rr

PAGE = Path(__file__).resolve().parents[2] / "docs" / "extending.md"


def _run_page() -> dict:
    blocks = re.findall(r"```python\n(.*?)```", PAGE.read_text(), flags=re.S)
    assert len(blocks) >= 3
    namespace: dict = {"__name__": "extending_page"}
    for block in blocks:
        exec(compile(block, str(PAGE), "exec"), namespace)  # noqa: S102 - our own docs page
    return namespace


def test_extending_page_worked_example_renders():
    ns = _run_page()
    image = np.asarray(ns["image"])
    assert image.shape == (ns["SIZE"], ns["SIZE"], 3) and np.all(np.isfinite(image))
    assert image.mean() > 0
    cls = ns["FujiiOrenNayar"]
    assert issubclass(cls, rr.AbstractMaterial) and cls.NAME == "fujii"


def test_extending_page_material_is_lambertian_at_zero_roughness():
    """Fujii's model with sigma = 0 is the Lambertian BRDF, so the user-defined plugin and the
    library's `Diffuse` give the same image for the same samples (an independent check that
    the plugin's rows, textures and BxDF are wired as the library's are)."""
    ns = _run_page()
    description = rr.load_scene("cornell-box")
    scene, camera, _ = rr.compile_scene(description, width=8, height=8)
    flat = [
        ns["FujiiOrenNayar"].from_properties({**m.params, "sigma": 0.0})
        for m in description.materials
    ]
    fujii = rr.RenderScene.from_triangles(
        description.vertices,
        description.faces,
        description.face_material,
        flat,
        description.face_emitter,
        scene.light.radiance,
    )
    kw = dict(camera=camera, spp=2, seed=3, integrator=rr.Path(max_depth=3), progress=False)
    ours = np.asarray(rr.render(fujii, **kw))
    ref = np.asarray(rr.render(scene, **kw))
    np.testing.assert_allclose(ours, ref, rtol=1e-5, atol=1e-6)
    assert jnp.asarray(ours).dtype == jnp.float32
