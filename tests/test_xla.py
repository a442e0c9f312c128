"""The renderer's XLA compile options (`radiometria._xla`): which options, when, and that they
reach the compiled programs."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from radiometria import _xla
from radiometria.render import _driver

_M = np.array([[0.5, 0.1, 0.0], [0.0, 0.4, 0.2], [0.3, 0.0, 0.6]])


def _small_products(p):
    """A path tracer's kind of work: (n, 3) points through a 3x3 matrix, summed over the axis."""
    return jnp.sum((p @ jnp.asarray(_M, p.dtype).T) * p, axis=-1)


@pytest.fixture
def clean_env(monkeypatch):
    monkeypatch.delenv(_xla.DEFAULTS_ENV, raising=False)
    monkeypatch.setenv("XLA_FLAGS", "--xla_force_host_platform_device_count=1")


def test_cpu_programs_compile_without_ynnpack_fusions(clean_env):
    """On the CPU the option is given and takes effect: the compiled program has no YNNPACK
    custom call, and computes what XLA's defaults and NumPy (float64) compute."""
    if not _xla.supported():
        pytest.skip("this jaxlib does not know the option: the renderer uses XLA's defaults")
    assert _xla.compiler_options("cpu") == {_xla.YNN_OPTION: ""}
    p = np.random.default_rng(0).uniform(size=(256, 3)).astype(np.float32)
    tuned = jax.jit(_small_products, **_xla.jit_options("cpu"))
    assert "ynn_fusion" not in tuned.lower(p).compile().as_text()
    default = jax.jit(_small_products)
    np.testing.assert_allclose(tuned(p), default(p), rtol=1e-6)
    expected = np.sum((p.astype(np.float64) @ _M.T) * p, axis=-1)
    np.testing.assert_allclose(tuned(p), expected, rtol=1e-5)


def test_options_are_left_out_where_they_do_not_apply(clean_env, monkeypatch):
    """Not on other platforms, not when the user's XLA_FLAGS sets the option, not with
    RADIOMETRIA_XLA_DEFAULTS, and never an argument `jax.jit` would not know."""
    assert _xla.compiler_options("gpu") == {} and _xla.jit_options("tpu") == {}
    monkeypatch.setenv("XLA_FLAGS", f"--{_xla.YNN_OPTION}=individual_dot")
    assert _xla.compiler_options("cpu") == {}
    monkeypatch.setenv("XLA_FLAGS", "")
    monkeypatch.setenv(_xla.DEFAULTS_ENV, "1")
    assert _xla.compiler_options("cpu") == {} and _xla.jit_options("cpu") == {}


def test_an_unknown_option_is_probed_as_unsupported():
    """The fallback: an option this jaxlib rejects is reported unsupported, not raised."""
    assert not _xla.supported("xla_radiometria_no_such_option", "1")
    assert not _xla.supported(_xla.YNN_OPTION, "no_such_fusion_type")


_MARKER = {"compiler_options": {"xla_radiometria_marker_option": "1"}}


def test_the_render_step_is_compiled_with_the_options(monkeypatch):
    """`render`'s step is compiled with `jit_options` of its devices' platform: an option XLA
    does not know, put there, stops the compile naming it."""
    from radiometria.render import Path as PathIntegrator, render

    from .render._synthetic import lit_box_camera, lit_box_scene

    platforms = []
    monkeypatch.setattr(_driver, "jit_options", lambda p: platforms.append(p) or _MARKER)
    monkeypatch.setattr(_driver, "_PROGRAMS", {})
    cam = lit_box_camera(4, 4)
    with pytest.raises(Exception, match="xla_radiometria_marker_option"):
        render(lit_box_scene(), camera=cam, spp=1, integrator=PathIntegrator(max_depth=1),
               progress=False)  # fmt: skip
    assert platforms == ["cpu"]


def test_the_warm_start_compiles_with_the_options(monkeypatch):
    """The command line's warm start compiles its deserialised programs with them too."""
    from radiometria import _warmstart

    blob = jax.export.export(jax.jit(_small_products))(
        jax.ShapeDtypeStruct((8, 3), jnp.float32)
    ).serialize()
    p = np.ones((8, 3), np.float32)
    np.testing.assert_allclose(_warmstart.exported_caller(bytes(blob), platform="cpu")(p),
                               _small_products(p), rtol=1e-6)  # fmt: skip
    monkeypatch.setattr(_warmstart, "jit_options", lambda p: _MARKER)
    with pytest.raises(Exception, match="xla_radiometria_marker_option"):
        _warmstart.exported_caller(bytes(blob))(p)
