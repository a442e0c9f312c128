"""Materials of the integrators: Mitsuba-style BSDF parameters as per-material spectral rows.

A scene's materials (`Material` of a loaded scene: Mitsuba's `diffuse`, `conductor`,
`roughconductor`, `dielectric`, `roughdielectric`, optionally `twosided`) become arrays with one
entry per material (`MaterialTables`), and at a hit `material_bxdf` builds the
`radiometria.scattering` BxDF of each path's material at its four hero wavelengths:

- `diffuse`: `DiffuseBxDF`; `reflectance` (default 0.5).
- `conductor`: `ConductorBxDF`; `material` (`"none"`, the default: a perfect mirror; `"Au"`,
  `"Ag"`, `"Cu"`, `"Al"`: measured tables) or `eta` and `k`; `specular_reflectance`.
- `roughconductor`: `RoughConductorBxDF`; as `conductor`, plus `alpha` (default 0.1).
- `dielectric`: `DielectricBxDF`; `int_ior` (default `"bk7"`), `ext_ior` (default `"air"`),
  `specular_reflectance`, `specular_transmittance`.
- `roughdielectric`: `RoughDielectricBxDF`; as `dielectric`, plus `alpha` (default 0.1).

Named indices of refraction are Mitsuba 3's constants (`MITSUBA_IOR`). Microfacet materials
use the Trowbridge-Reitz (GGX) distribution of `radiometria.scattering` whatever the scene's
`distribution` says (Mitsuba's default is Beckmann; the two differ in the tails of the
highlight). Anisotropic `alpha_u`/`alpha_v` are used as given.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from ..scattering import (
    BSDFSample,
    ConductorBxDF,
    DielectricBxDF,
    DiffuseBxDF,
    RoughConductorBxDF,
    RoughDielectricBxDF,
)
from ._spectral import SpectrumTable, spectrum_values, wavelength_grid_nm

__all__ = ["MATERIAL_KINDS", "MITSUBA_IOR", "MaterialTables", "material_bxdf"]

MATERIAL_KINDS = ("diffuse", "conductor", "roughconductor", "dielectric", "roughdielectric")
TRANSMISSIVE_KINDS = ("dielectric", "roughdielectric")

# Mitsuba 3's named indices of refraction (documentation of the `dielectric` plugin).
MITSUBA_IOR = {
    "vacuum": 1.0,
    "helium": 1.00004,
    "hydrogen": 1.00013,
    "air": 1.00028,
    "carbon dioxide": 1.00045,
    "water": 1.3330,
    "acetone": 1.36,
    "ethanol": 1.361,
    "carbon tetrachloride": 1.461,
    "glycerol": 1.4729,
    "benzene": 1.501,
    "silicone oil": 1.52045,
    "bromine": 1.661,
    "water ice": 1.31,
    "fused quartz": 1.458,
    "pyrex": 1.470,
    "acrylic glass": 1.49,
    "polypropylene": 1.49,
    "bk7": 1.5046,
    "sodium chloride": 1.544,
    "amber": 1.55,
    "pet": 1.5750,
    "diamond": 2.419,
}
_PERFECT_MIRROR_K = 1e3  # eta = 1, k = 1e3: Fresnel reflectance 1 - 4e-6 (Mitsuba's "none")


class MaterialTables(eqx.Module):
    """Per-material parameters as arrays (one row per material; spectra on the 1 nm grid).

    **Fields:**

    - `kind`: `(m,)` int32 index into `MATERIAL_KINDS`.
    - `kinds`: the kinds present (static), which `material_bxdf` dispatches over.
    - `reflectance`: diffuse reflectance, or the `specular_reflectance` factor. [1]
    - `transmittance`: the `specular_transmittance` factor of dielectrics (1 otherwise). [1]
    - `eta`, `k`: conductor index `eta + i k`; for dielectrics `eta` = int_ior / ext_ior. [1]
    - `alpha_u`, `alpha_v`: `(m,)` microfacet roughness. [1]
    - `two_sided`: `(m,)` bool, scatter on both sides (Mitsuba's `twosided`).
    - `transmissive`: `(m,)` bool, dielectric kinds (both sides are surfaces of the medium).

    !!! note "Thesis"
        Chapter 3 (BSDFs of surfaces, eq. 3.4; Fresnel equations 3.13-3.18).

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's `diffuse`, `conductor`, `dielectric` and rough variants).
    """

    kind: Array
    reflectance: SpectrumTable
    transmittance: SpectrumTable
    eta: SpectrumTable
    k: SpectrumTable
    alpha_u: Array
    alpha_v: Array
    two_sided: Array
    transmissive: Array
    kinds: tuple = eqx.field(static=True)

    @classmethod
    def lambertian(cls, reflectance: SpectrumTable, two_sided) -> "MaterialTables":
        """Lambertian materials with the given reflectance rows; `two_sided` `(m,)` bool."""
        m = reflectance.values.shape[0]
        ones = SpectrumTable(jnp.ones_like(reflectance.values))
        return cls(
            kind=jnp.zeros((m,), jnp.int32),
            reflectance=reflectance,
            transmittance=ones,
            eta=ones,
            k=SpectrumTable(jnp.zeros_like(reflectance.values)),
            alpha_u=jnp.full((m,), 0.1, jnp.float32),
            alpha_v=jnp.full((m,), 0.1, jnp.float32),
            two_sided=jnp.asarray(two_sided, bool).reshape(m),
            transmissive=jnp.zeros((m,), bool),
            kinds=(0,),
        )

    @classmethod
    def from_materials(cls, materials, where: str = "scene") -> "MaterialTables":
        """Tabulate `Material`s of a loaded scene (see the module docstring)."""
        n = wavelength_grid_nm().shape[0]
        ones = np.ones(n)
        rows = {name: [] for name in ("reflectance", "transmittance", "eta", "k")}
        kind, alpha_u, alpha_v = [], [], []
        for m in materials:
            if m.type not in MATERIAL_KINDS:
                raise ValueError(
                    f"{where}: material {m.name!r} has type {m.type!r}; supported: "
                    f"{', '.join(MATERIAL_KINDS)}."
                )
            p = m.params
            kind.append(MATERIAL_KINDS.index(m.type))
            if m.type == "diffuse":
                refl = spectrum_values(p.get("reflectance", {"value": 0.5}), "albedo")
            else:
                refl = spectrum_values(p.get("specular_reflectance", {"value": 1.0}), "unbounded")
            trans = spectrum_values(p.get("specular_transmittance", {"value": 1.0}), "unbounded")
            eta, k = ones, 0.0 * ones
            if m.type in ("conductor", "roughconductor"):
                eta, k = _conductor_ior(p, m.name, where)
            elif m.type in TRANSMISSIVE_KINDS:
                eta = _ior(p.get("int_ior", {"name": "bk7"}), m.name, where) / _ior(
                    p.get("ext_ior", {"name": "air"}), m.name, where
                )
            a = p.get("alpha", {"value": 0.1})["value"]
            alpha_u.append(p.get("alpha_u", {"value": a})["value"])
            alpha_v.append(p.get("alpha_v", {"value": a})["value"])
            for name, value in zip(rows, (refl, trans, eta, k), strict=True):
                rows[name].append(value)

        def table(name):
            return SpectrumTable(jnp.asarray(np.stack(rows[name]), jnp.float32))

        kinds = tuple(sorted(set(kind)))
        return cls(
            kind=jnp.asarray(kind, jnp.int32),
            reflectance=table("reflectance"),
            transmittance=table("transmittance"),
            eta=table("eta"),
            k=table("k"),
            alpha_u=jnp.asarray(alpha_u, jnp.float32),
            alpha_v=jnp.asarray(alpha_v, jnp.float32),
            two_sided=jnp.asarray([m.two_sided for m in materials], bool),
            transmissive=jnp.asarray([m.type in TRANSMISSIVE_KINDS for m in materials], bool),
            kinds=kinds,
        )


def _ior(spec: dict, name: str, where: str) -> np.ndarray:
    if "name" in spec:
        key = spec["name"].lower()
        if key not in MITSUBA_IOR:
            raise ValueError(
                f"{where}: material {name!r}: unknown index of refraction {spec['name']!r}; "
                f"known: {', '.join(MITSUBA_IOR)}."
            )
        return np.full(wavelength_grid_nm().shape, MITSUBA_IOR[key])
    values = spectrum_values(spec, "unbounded" if "rgb" in spec else "albedo")
    if np.any(values[(values != 0)] <= 0) or np.all(values == 0):
        raise ValueError(f"{where}: material {name!r}: indices of refraction must be > 0.")
    return values


def _conductor_ior(p: dict, name: str, where: str) -> tuple[np.ndarray, np.ndarray]:
    grid = wavelength_grid_nm()
    if "eta" in p or "k" in p:
        return (
            spectrum_values(p.get("eta", {"value": 0.0}), "unbounded"),
            spectrum_values(p.get("k", {"value": 1.0}), "unbounded"),
        )
    material = p.get("material", "none")
    if material == "none":
        return np.ones(grid.shape), np.full(grid.shape, _PERFECT_MIRROR_K)
    from ..scattering import CONDUCTORS, get_conductor

    if material not in CONDUCTORS:
        raise ValueError(
            f"{where}: material {name!r}: unknown conductor {material!r}; known: 'none', "
            f"{', '.join(map(repr, CONDUCTORS))}."
        )
    eta, k = get_conductor(material)(jnp.asarray(grid))
    return np.asarray(eta, np.float64), np.asarray(k, np.float64)


class _Mixture(eqx.Module):
    """The BxDFs of several material kinds, one chosen per path by `kind` (`where` selects)."""

    kind: Array  # (n,) index into MATERIAL_KINDS
    parts: tuple  # ((kind index, BxDF, reflection scale, transmission scale), ...)

    def _pick(self, values):
        out = values[0]
        for (kid, *_), v in zip(self.parts[1:], values[1:], strict=True):
            mask = (self.kind == kid).reshape(self.kind.shape + (1,) * (v.ndim - 1))
            out = jnp.where(mask, v, out)
        return out

    def f(self, wo, wi):
        reflection = (wo[..., 2] * wi[..., 2] > 0)[..., None]
        return self._pick([b.f(wo, wi) * jnp.where(reflection, r, t) for _, b, r, t in self.parts])

    def pdf(self, wo, wi):
        return self._pick([b.pdf(wo, wi) for _, b, _, _ in self.parts])

    def sample_f(self, wo, u_lobe, u2):
        samples = [b.sample_f(wo, u_lobe, u2) for _, b, _, _ in self.parts]
        scaled = [
            s.f * jnp.where(s.is_transmission[..., None], t, r)
            for s, (_, _, r, t) in zip(samples, self.parts, strict=True)
        ]
        return BSDFSample(
            f=self._pick(scaled),
            wi=self._pick([s.wi for s in samples]),
            pdf=self._pick([s.pdf for s in samples]),
            is_delta=self._pick([s.is_delta for s in samples]),
            is_transmission=self._pick([s.is_transmission for s in samples]),
            eta=self._pick([s.eta for s in samples]),
            terminate_secondary=self._pick([s.terminate_secondary for s in samples]),
        )


def material_bxdf(tables: MaterialTables, material, wavelength_nm):
    """The BxDF of each path's material at its wavelengths (`(n,)` materials, `(n, k)` nm).

    A scene with one kind of material gets that kind's `radiometria.scattering` BxDF itself;
    otherwise a mixture that evaluates each kind present and selects per path.
    """
    refl = tables.reflectance(material, wavelength_nm)
    if tables.kinds == (0,):
        return DiffuseBxDF(refl)
    trans = tables.transmittance(material, wavelength_nm)
    # Keep every kind's parameters valid on the paths of other kinds (the BxDF constructors
    # check their ranges): an index > 0, k >= 0.
    eta = jnp.maximum(tables.eta(material, wavelength_nm), 1e-3)
    k = jnp.maximum(tables.k(material, wavelength_nm), 0.0)
    au, av = tables.alpha_u[material], tables.alpha_v[material]
    one = jnp.ones_like(refl)
    parts = []
    for kid in tables.kinds:
        kind = MATERIAL_KINDS[kid]
        if kind == "diffuse":
            parts.append((kid, DiffuseBxDF(jnp.clip(refl, 0.0, 1.0)), one, one))
        elif kind == "conductor":
            parts.append((kid, ConductorBxDF(eta, k), refl, refl))
        elif kind == "roughconductor":
            parts.append((kid, RoughConductorBxDF(au, eta, k, av), refl, refl))
        elif kind == "dielectric":
            parts.append((kid, DielectricBxDF(eta), refl, trans))
        else:
            parts.append((kid, RoughDielectricBxDF(au, eta, av), refl, trans))
    if len(parts) == 1 and MATERIAL_KINDS[parts[0][0]] == "diffuse":
        return parts[0][1]
    return _Mixture(tables.kind[material], tuple(parts))
