"""Textures (issue 12) and hostile texture files (issue 16).

Lookups are checked against values computed by hand from the image data (grey texels have
exactly flat spectra, so a lookup is a number), colour lookups against the upsampling
module's own spectra of the texels, sRGB decoding against colour-science, and a textured
scene against Mitsuba 3 `scalar_spectral` with the per-pixel z-test.

CI runs a bounded number of fuzz examples; `RADIOMETRIA_FUZZ_EXAMPLES=5000 pytest -m fuzz`
runs a longer search.
"""

import struct
import time
import zlib

import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, strategies as st
from PIL import Image

from radiometria.render import RenderScene, SceneError, load_scene
from radiometria.render._integrators._path import path_radiance, sample_dimensions
from radiometria.render._materials import Diffuse, MaterialSet
from radiometria.render._spectral import (
    LinearRGB,
    SpectrumTable,
    sigmoid_texel_spectra,
    tabulate_spectrum,
)
from radiometria.render._textures import (
    BitmapTexture,
    CheckerboardTexture,
    ConstantTexture,
    TextureFileError,
    TextureStack,
    concatenate_textures,
    read_texture_image,
)
from radiometria.upsampling import (
    RGBAlbedoSpectrum,
    RGBIlluminantSpectrum,
    get_lut,
    sigmoid_polynomial_jakob2019,
)

from ..helpers import fuzz_settings, mutate_bytes

GREYS = np.array([[0.1, 0.3], [0.5, 0.9]])  # row 0 is the top of the image


def _grey_texture(**kw) -> BitmapTexture:
    return BitmapTexture.from_rgb(np.repeat(GREYS[..., None], 3, axis=2), dtype=jnp.float64, **kw)


def _lookup(tex, uv) -> np.ndarray:
    uv = jnp.asarray(uv, jnp.float64).reshape(-1, 2)
    wl = jnp.tile(jnp.asarray([[420.0, 500.0, 580.0, 700.0]]), (uv.shape[0], 1))
    out = np.asarray(tex(jnp.zeros(uv.shape[0], jnp.int32), wl, uv))
    return out


@pytest.mark.parametrize(
    ("filter_type", "wrap_mode", "uv", "expected"),
    [
        # nearest: texel (column floor(u w), row floor(v h))
        ("nearest", "repeat", [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)],
         [0.1, 0.3, 0.5, 0.9]),
        ("nearest", "repeat", [(1.25, 0.25), (-0.25, 0.25)], [0.1, 0.3]),
        ("nearest", "clamp", [(1.25, 0.25), (-0.25, 0.25)], [0.3, 0.1]),
        ("nearest", "mirror", [(1.25, 0.25), (-0.25, 0.25), (2.25, 0.25)], [0.3, 0.1, 0.1]),
        # bilinear: texel centres at (i + 1/2) / w
        ("bilinear", "repeat", [(0.25, 0.25), (0.5, 0.25), (0.5, 0.5), (0.25, 0.5)],
         [0.1, 0.2, 0.45, 0.3]),
        ("bilinear", "repeat", [(0.0, 0.25)], [0.2]),  # halfway between columns 1 and 0
        ("bilinear", "clamp", [(0.0, 0.25), (1.0, 0.75)], [0.1, 0.9]),
        ("bilinear", "mirror", [(0.0, 0.25), (1.0, 0.75)], [0.1, 0.9]),
    ],
)  # fmt: skip
def test_bitmap_lookup_of_a_2x2_grey_image(filter_type, wrap_mode, uv, expected):
    tex = _grey_texture(filter_type=filter_type, wrap_mode=wrap_mode)
    out = _lookup(tex, uv)
    np.testing.assert_allclose(out, np.repeat(np.asarray(expected)[:, None], 4, 1), atol=1e-6)


def test_bitmap_to_uv_transform_maps_uv_before_the_lookup():
    # Mitsuba's to_uv 4x4: u' = 2 u + 0.25, v' = 0.5 v (rows/columns 0, 1, 3 of the matrix).
    m = np.eye(4)
    m[0, 0], m[0, 3], m[1, 1] = 2.0, 0.25, 0.5
    tex = _grey_texture(filter_type="nearest", to_uv=m)
    # (0.1, 0.9) -> (0.45, 0.45): texel (0, 0); (0.3, 1.2) -> (0.85, 0.6): texel (1, 1).
    np.testing.assert_allclose(_lookup(tex, [(0.1, 0.9), (0.3, 1.2)])[:, 0], [0.1, 0.9], 1e-6)


def test_bilinear_colour_lookup_interpolates_the_texel_spectra():
    rng = np.random.default_rng(3)
    rgb = rng.uniform(0.02, 0.98, (3, 4, 3))
    tex = BitmapTexture.from_rgb(rgb, dtype=jnp.float64)
    u, v = 0.3, 0.55  # x = u w - 1/2 = 0.7, y = v h - 1/2 = 1.15
    wl = np.array([420.0, 500.0, 580.0, 700.0])
    lut = get_lut("sRGB")

    def spectrum(j, i):
        return np.asarray(RGBAlbedoSpectrum(lut, rgb[j, i])(jnp.asarray(wl)))

    top = 0.3 * spectrum(1, 0) + 0.7 * spectrum(1, 1)
    bottom = 0.3 * spectrum(2, 0) + 0.7 * spectrum(2, 1)
    expected = 0.85 * top + 0.15 * bottom
    np.testing.assert_allclose(_lookup(tex, [(u, v)])[0], expected, rtol=1e-9)


def test_black_and_white_texels_interpolate_without_nans():
    # The table's coefficients of black and white are infinite; spectra are interpolated.
    tex = BitmapTexture.from_rgb(np.array([[[0.0] * 3, [1.0] * 3]]), dtype=jnp.float64)
    np.testing.assert_allclose(_lookup(tex, [(0.5, 0.5)]), 0.5, atol=1e-12)


def test_texel_spectra_wavelengths_first_equal_the_model():
    # `sigmoid_texel_spectra` ((k, n), coefficient planes) against the upsampling module's
    # own evaluation of each gathered texel; black and white texels' infinite coefficients
    # give exactly 0 and 1.
    rng = np.random.default_rng(4)
    rgb = np.concatenate([rng.uniform(0.02, 0.98, (10, 3)), [[0.0] * 3, [1.0] * 3]])
    coeffs = np.asarray(get_lut("sRGB").coefficients(jnp.asarray(rgb)), np.float64)  # (12, 3)
    texel = rng.integers(0, 12, 50)
    wl = rng.uniform(360.0, 830.0, (50, 4))
    out = sigmoid_texel_spectra(jnp.asarray(coeffs.T), jnp.asarray(texel), jnp.asarray(wl.T))
    expected = sigmoid_polynomial_jakob2019(jnp.asarray(coeffs[texel]), jnp.asarray(wl))
    np.testing.assert_allclose(np.asarray(out).T, np.asarray(expected), rtol=1e-12, atol=0)
    assert set(np.unique(np.asarray(out)[:, texel >= 10])) <= {0.0, 1.0}


def test_checkerboard_against_hand_parity():
    tex = CheckerboardTexture.from_values(0.4, 0.2, dtype=jnp.float64)
    rng = np.random.default_rng(0)
    uv = rng.uniform(-3, 3, (64, 2))
    f = uv - np.floor(uv)
    expected = np.where((f[:, 0] > 0.5) == (f[:, 1] > 0.5), 0.4, 0.2)
    np.testing.assert_allclose(_lookup(tex, uv)[:, 0], expected, atol=1e-12)


def test_materials_of_one_kind_with_different_textures_form_a_stack():
    grey = _grey_texture(filter_type="nearest")
    constant = ConstantTexture.from_values([0.7], RGBAlbedoSpectrum, jnp.float64)
    stacked = concatenate_textures([constant, grey, constant])
    assert isinstance(stacked, TextureStack) and stacked.n_rows == 3
    mats = MaterialSet.from_materials(
        [Diffuse(constant, jnp.zeros(1, bool)), Diffuse(grey, jnp.zeros(1, bool))]
    )
    wl = jnp.full((2, 4), 550.0)
    uv = jnp.asarray([[0.75, 0.75], [0.75, 0.75]])
    wo = wi = jnp.asarray([[0.0, 0.0, 1.0]] * 2)
    f = np.asarray(mats.bxdf(jnp.asarray([0, 1]), wl, uv).f(wo, wi))
    np.testing.assert_allclose(f[:, 0] * np.pi, [0.7, 0.9], rtol=1e-5)


def test_a_uniform_texture_renders_as_the_constant_reflectance():
    floor = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    lamp = np.array([[-0.3, -0.3, 1], [-0.3, 0.3, 1], [0.3, 0.3, 1], [0.3, -0.3, 1]], float)
    vertices = np.concatenate([floor, lamp])
    faces = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    rgb = [0.2, 0.5, 0.7]
    radiance = SpectrumTable(
        jnp.asarray(tabulate_spectrum(LinearRGB([5.0, 5.0, 5.0]), RGBIlluminantSpectrum)[None])
    )
    images = []
    for texture in (
        ConstantTexture.from_values([LinearRGB(rgb)], RGBAlbedoSpectrum),
        BitmapTexture.from_rgb(np.tile(np.asarray(rgb), (3, 2, 1))),
    ):
        scene = RenderScene.from_triangles(
            vertices, faces, [0, 0, 0, 0], [Diffuse(texture, jnp.zeros(1, bool))],
            [-1, -1, 0, 0], radiance,
            face_uv=np.random.default_rng(1).uniform(-2, 2, (4, 3, 2)),
        )  # fmt: skip
        rng = np.random.default_rng(2)
        n = 512
        o = np.column_stack([rng.uniform(-0.9, 0.9, (n, 2)), np.full(n, 0.5)])
        d = np.tile([0.0, 0.0, -1.0], (n, 1))
        wl = rng.uniform(400, 700, (n, 4))
        u = rng.uniform(size=(n, sample_dimensions(3)))
        images.append(
            np.asarray(
                path_radiance(
                    scene, *(jnp.asarray(x, jnp.float32) for x in (o, d, wl, u)), max_depth=3
                )
            )  # fmt: skip
        )
    assert images[0].max() > 0
    np.testing.assert_allclose(images[1], images[0], rtol=2e-5, atol=1e-7)


def test_srgb_decoding_of_8_bit_images_matches_colour_science(tmp_path):
    colour = pytest.importorskip("colour")
    levels = np.arange(0, 256, 17, dtype=np.uint8)  # 16 levels
    img = np.stack([levels, levels[::-1], np.full(16, 128, np.uint8)], -1).reshape(4, 4, 3)
    Image.fromarray(img).save(tmp_path / "t.png")
    got = read_texture_image(tmp_path / "t.png")
    expected = colour.cctf_decoding(img / 255.0, function="sRGB")
    np.testing.assert_allclose(got, expected, atol=1e-12)
    np.testing.assert_allclose(read_texture_image(tmp_path / "t.png", raw=True), img / 255.0)
    Image.fromarray(img[..., 0]).save(tmp_path / "g.bmp")  # grey: three equal channels
    np.testing.assert_allclose(
        read_texture_image(tmp_path / "g.bmp"), expected[..., :1] * [1, 1, 1]
    )


# -- scenes ------------------------------------------------------------------------------------

SCENE = """<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="2"/></integrator>
<sensor type="perspective"><float name="fov" value="50"/>
 <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
 <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
 <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>
 <rfilter type="box"/></film></sensor>
<texture type="checkerboard" id="chk"><rgb name="color0" value="0.8, 0.1, 0.1"/>
 <rgb name="color1" value="0.1, 0.2, 0.7"/>
 <transform name="to_uv"><scale x="3" y="2"/></transform></texture>
<shape type="rectangle"><transform name="to_world"><translate x="-1"/></transform>
 <bsdf type="diffuse">{bitmap}</bsdf></shape>
<shape type="rectangle"><transform name="to_world"><translate x="1"/></transform>
 <bsdf type="diffuse"><ref name="reflectance" id="chk"/></bsdf></shape>
<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>"""
BITMAP = """<texture type="bitmap" name="reflectance"><string name="filename" value="{f}"/>
 <string name="filter_type" value="{filt}"/><string name="wrap_mode" value="{wrap}"/>{extra}
 </texture>"""


def _scene(tmp_path, w=16, h=16, f="tex.png", filt="bilinear", wrap="repeat", extra=""):
    bitmap = BITMAP.format(f=f, filt=filt, wrap=wrap, extra=extra)
    path = tmp_path / "scene.xml"
    path.write_text(SCENE.format(w=w, h=h, bitmap=bitmap))
    return path


def _image(tmp_path, shape=(4, 4, 3), seed=0):
    rng = np.random.default_rng(seed)
    Image.fromarray(rng.integers(0, 256, shape, dtype=np.uint8)).save(tmp_path / "tex.png")


@pytest.mark.slow
def test_textured_scene_passes_the_z_test_against_mitsuba(tmp_path):
    pytest.importorskip("mitsuba")
    from ._mitsuba import z_test_against_mitsuba

    _image(tmp_path)
    path = _scene(tmp_path, extra='<transform name="to_uv"><scale x="1.5"/></transform>')
    result = z_test_against_mitsuba(path, spp=64, ref_spp=512)
    assert result.passed, result.message


# -- hostile texture files (issue 16) -----------------------------------------------------------


def _png_header(width: int, height: int) -> bytes:
    """A PNG whose header declares width x height RGB8 texels, with a few bytes of data."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    idat = zlib.compress(bytes(64))
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def _bitmap_line(path) -> int:
    lines = path.read_text().splitlines()
    return next(i + 1 for i, line in enumerate(lines) if 'type="bitmap"' in line)


def _hostile(tmp_path, name: str, data: bytes | None):
    if data is not None:
        (tmp_path / name).write_bytes(data)
    return _scene(tmp_path, f=name)


def _valid_png() -> bytes:
    import io

    buf = io.BytesIO()
    Image.fromarray(np.arange(48, dtype=np.uint8).reshape(4, 4, 3)).save(buf, format="PNG")
    return buf.getvalue()


@pytest.mark.parametrize(
    ("name", "data", "message"),
    [
        ("garbage.png", b"\x00\xffnot an image at all" * 10, "not a readable image"),
        ("truncated.png", _valid_png()[:45], "not a readable image"),
        ("big.png", _png_header(9000, 9000), "declares 9000 x 9000 texels"),
        ("bomb.png", _png_header(100_000, 100_000), "image too large"),
        ("empty.png", b"", "not a readable image"),
        ("pic.hdr", b"#?RADIANCE\n", "not a readable Radiance RGBE texture"),
        ("pic.gif2", b"GIF89a", "unsupported texture format"),
        ("bad.exr", b"v/1\x01" + b"\x00" * 40, "not a readable RGB OpenEXR texture"),
    ],
)
def test_hostile_texture_file_is_a_scene_error_naming_scene_line_and_file(
    tmp_path, name, data, message
):
    path = _hostile(tmp_path, name, data)
    start = time.monotonic()
    with pytest.raises(SceneError) as info:
        load_scene(path)
    text = str(info.value)
    assert text.startswith(f"{path}:{_bitmap_line(path)}:"), text  # the <texture>'s line
    assert name in text and message in text, text
    assert time.monotonic() - start < 10.0


def test_cmyk_texture_is_refused_with_its_pixel_format(tmp_path):
    Image.new("CMYK", (4, 4)).save(tmp_path / "cmyk.jpg")
    with pytest.raises(SceneError, match=r"cmyk.jpg: unsupported pixel format 'CMYK'"):
        load_scene(_scene(tmp_path, f="cmyk.jpg"))


def test_missing_texture_file_names_scene_and_file(tmp_path):
    path = _scene(tmp_path, f="nowhere.png")
    with pytest.raises(FileNotFoundError, match=rf"{path}:{_bitmap_line(path)}: .*nowhere.png"):
        load_scene(path)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ("", "filter_type must be one of"),  # filt="cubic" below
        ('<float name="scale" value="2"/>', "unsupported parameter 'scale'"),
        ('<boolean name="raw" value="maybe"/>', "expected true or false"),
    ],
)
def test_bad_bitmap_parameters_are_named(tmp_path, extra, message):
    _image(tmp_path)
    path = _scene(tmp_path, filt="cubic" if not extra else "nearest", extra=extra)
    with pytest.raises(SceneError, match=message):
        load_scene(path)


def test_texture_where_none_is_supported_is_named(tmp_path):
    _image(tmp_path)
    text = (
        _scene(tmp_path)
        .read_text()
        .replace(
            '<emitter type="constant"><rgb name="radiance" value="1"/></emitter>',
            '<emitter type="constant"><ref name="radiance" id="chk"/></emitter>',
        )
    )
    (tmp_path / "scene.xml").write_text(text)
    with pytest.raises(SceneError, match=r"scene.xml:\d+: <(ref|emitter)"):
        load_scene(tmp_path / "scene.xml")
    text = text.replace('<ref name="radiance" id="chk"/>', '<rgb name="radiance" value="1"/>')
    text = text.replace(
        '<bsdf type="diffuse"><ref name="reflectance" id="chk"/></bsdf>',
        '<bsdf type="dielectric"><ref name="int_ior" id="chk"/></bsdf>',
    )  # Mitsuba's int_ior is a number (a conductor's eta and k are textures, as in Mitsuba)
    (tmp_path / "scene.xml").write_text(text)
    with pytest.raises(SceneError, match="a texture is not supported for parameter 'int_ior'"):
        load_scene(tmp_path / "scene.xml")


BYTE_MUTATION = st.tuples(
    st.sampled_from(["delete", "insert", "flip", "truncate"]),
    st.integers(min_value=0, max_value=10**6),
    st.integers(min_value=0, max_value=32),
    st.binary(max_size=8),
)


def _sources() -> dict:
    import io

    out = {}
    img = np.random.default_rng(0).integers(0, 256, (6, 5, 3), dtype=np.uint8)
    for name, fmt in (("t.png", "PNG"), ("t.jpg", "JPEG"), ("t.bmp", "BMP")):
        buf = io.BytesIO()
        Image.fromarray(img).save(buf, format=fmt)
        out[name] = buf.getvalue()
    return out


SOURCES = _sources()


@pytest.mark.fuzz
@fuzz_settings(30)
@given(
    source=st.sampled_from(sorted(SOURCES)),
    mutations=st.lists(BYTE_MUTATION, min_size=1, max_size=4),
)
def test_mutated_image_reads_or_raises_texture_file_error(tmp_path, source, mutations):
    path = tmp_path / source
    path.write_bytes(mutate_bytes(SOURCES[source], mutations))
    start = time.monotonic()
    try:
        rgb = read_texture_image(path)
    except TextureFileError as e:
        assert str(e).startswith(f"{path}: "), e
    else:
        assert rgb.ndim == 3 and rgb.shape[2] == 3 and np.isfinite(rgb).all()
        assert rgb.min() >= 0 and rgb.max() <= 1
    assert time.monotonic() - start < 10.0, "reading a small mutated image took over 10 s"
