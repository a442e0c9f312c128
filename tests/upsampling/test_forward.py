"""The forward model's NumPy evaluation equals the JAX colorimetry it stands for.

`upsampling.forward_model` computes its weights with NumPy (a render's start-up would
otherwise trace, lower and load a JAX program for them); the reference here is
`colorimetry.tristimulus_weights` and `jnp.interp` / `colorimetry.daylight_spd` in float64,
the functions the model was computed with before.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import radiometria.colorimetry as cm
import radiometria.upsampling as up
from radiometria.upsampling._forward import ACES_WHITE_CCT

SPACES = ["sRGB", "ProPhoto RGB", "ACES2065-1"]  # D65, D50 (tabulated) and daylight (ACES)


def _jax_model(space: str, step_nm: float):
    """(illuminant, white-balanced reflective weights, normalised illuminant) with JAX."""
    cs = cm.get_colourspace(space)
    n = int(round(470 / step_nm)) + 1
    with jax.enable_x64(True):
        wl = jnp.linspace(360.0, 830.0, n, dtype=jnp.float64)
        if cs.whitepoint_name == "ACES":
            ill = cm.daylight_spd(ACES_WHITE_CCT, wl)
        else:
            table = cm.get_illuminant(cs.whitepoint_name)
            ill = jnp.interp(wl, table.wavelengths_nm, table.values)
        w_xyz = np.asarray(cm.tristimulus_weights(wl, ill))
        w_emissive = np.asarray(cm.tristimulus_weights(wl, None))
        ill = np.asarray(ill)
    to_xyz = np.asarray(cs.matrix_RGB_to_XYZ, np.float64)
    w_rgb = w_xyz @ np.asarray(cs.matrix_XYZ_to_RGB, np.float64).T
    w_bal = (w_rgb / w_rgb.sum(axis=0)) @ to_xyz.T
    ill_n = ill * w_emissive[:, 1].sum() / (ill * w_emissive[:, 1]).sum()
    return w_bal, ill_n


@pytest.mark.parametrize("space", SPACES)
@pytest.mark.parametrize("step_nm", [1.0, 5.0])
def test_numpy_forward_model_equals_the_jax_colorimetry(space, step_nm):
    model = up.forward_model(space, step_nm=step_nm)
    w_bal, ill_n = _jax_model(space, step_nm)
    assert model.weights_XYZ.dtype == np.float64 and model.illuminant.dtype == np.float64
    np.testing.assert_allclose(model.weights_XYZ, w_bal, rtol=1e-13, atol=1e-17)
    np.testing.assert_allclose(model.illuminant, ill_n, rtol=1e-13)
