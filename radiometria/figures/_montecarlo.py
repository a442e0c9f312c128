"""Figures for `radiometria.montecarlo` (thesis ch. 5-7): point sets, convergence, variance."""

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from .. import montecarlo as mc
from ._registry import figure, save


def point_sets_data(*, smoke: bool = False) -> dict:
    """What fig. 5 (point sets) plots: `{"n", "side", "sets": [(title, points (n, 2)), ...]}`.

    n = 256 points (64 in smoke mode) of each generator of `radiometria.montecarlo`, key 0
    split four ways: `independent`, `stratified` (side x side jittered, side = sqrt(n)),
    `latin_hypercube`, `halton` (bases 2, 3, unscrambled), `sobol` (Joe-Kuo, unscrambled) and
    `sobol(scramble="owen")`, all in $[0, 1)^2$.
    """
    n = 64 if smoke else 256
    side = int(round(math.sqrt(n)))
    keys = jax.random.split(jax.random.key(0), 4)
    sets = [
        ("independent", mc.independent(n, 2, key=keys[0])),
        (f"stratified {side}x{side}", mc.stratified((side, side), key=keys[1])),
        ("Latin hypercube", mc.latin_hypercube(n, 2, key=keys[2])),
        ("Halton (2, 3)", mc.halton(n, 2)),
        ("Sobol (Joe-Kuo)", mc.sobol(n, 2)),
        ("Sobol, Owen-scrambled", mc.sobol(n, 2, scramble="owen", key=keys[3])),
    ]
    return {"n": n, "side": side, "sets": [(t, np.asarray(p)) for t, p in sets]}


@figure("fig_5_point_sets")
def fig_5_point_sets(out_dir, *, smoke: bool = False):
    """Two-dimensional point sets side by side (thesis ch. 5).

    Independent uniform, jittered stratified, Latin hypercube, Halton (bases 2, 3), Sobol
    (Joe-Kuo) and Owen-scrambled Sobol, 256 points each (64 in smoke mode), with the 16 x 16
    grid that a (0, 8, 2)-net fills with exactly one point per elementary interval. The data
    are `point_sets_data()`.
    """
    import matplotlib.pyplot as plt

    data = point_sets_data(smoke=smoke)
    n, side, sets = data["n"], data["side"], data["sets"]
    fig, axes = plt.subplots(1, len(sets), figsize=(3.0 * len(sets), 3.3), layout="constrained")
    for ax, (title, pts) in zip(axes, sets, strict=True):
        for t in np.linspace(0, 1, side + 1):
            ax.axhline(t, color="0.88", lw=0.5, zorder=0)
            ax.axvline(t, color="0.88", lw=0.5, zorder=0)
        ax.scatter(pts[:, 0], pts[:, 1], s=6, color="tab:blue")
        ax.set(xlim=(0, 1), ylim=(0, 1), aspect="equal", title=f"{title}, n = {n}")
        ax.set(xticks=[0, 1], yticks=[0, 1])
    return save(fig, out_dir, "fig_5_point_sets")


_GENZ_PROBLEMS = [
    ("Gaussian, d = 2", "gaussian", 2),
    ("oscillatory, d = 4", "oscillatory", 4),
    ("continuous (kinked), d = 3", "continuous", 3),
    ("discontinuous, d = 2", "discontinuous", 2),
]
_CONVERGENCE_METHODS = [
    ("mc", "independent"),
    ("lhs", "Latin hypercube"),
    ("halton", "Halton (Owen)"),
    ("sobol", "Sobol (Owen)"),
]


def convergence_figure_data(
    *, smoke: bool = False, n_replicates: int | None = None, methods=None
) -> dict:
    """What fig. 6 (convergence) plots: `convergence_study` of four Genz integrands.

    `ns`: 2^4 ... 2^8 in smoke mode, else 2^4 ... 2^14; `problems`: one dict per integrand
    (Gaussian d = 2, oscillatory d = 4, continuous d = 3, discontinuous d = 2, parameters
    `a`, `w` drawn from `numpy.random.default_rng(6)`) with `title`, `kind`, `dim`, `a`,
    `w`, `f`, `exact` (the closed-form integral from `genz`) and `studies`,
    `{method: ConvergenceStudy}` for `"mc"`, `"lhs"`, `"halton"`, `"sobol"` (Owen-scrambled
    QMC), each with `n_replicates` independent replicates (default 6 in smoke mode, else 48;
    key 6 split per study): the RMSE (len(ns),) and the fitted log-log `slope`. `methods`
    restricts the studies to a subset of those names (`None`: all four, as plotted).
    """
    ks = range(4, 9) if smoke else range(4, 15)
    ns = [2**k for k in ks]
    if n_replicates is None:
        n_replicates = 6 if smoke else 48
    rng = np.random.default_rng(6)
    key = jax.random.key(6)
    problems = []
    for title, kind, d in _GENZ_PROBLEMS:
        a, w = rng.uniform(0.5, 1.5, d), rng.uniform(0.2, 0.8, d)
        f, exact = mc.genz(kind, a, w)
        studies = {}
        for method, _ in _CONVERGENCE_METHODS:
            if methods is not None and method not in methods:
                continue
            key, sub = jax.random.split(key)
            studies[method] = mc.convergence_study(
                f, exact, ns, method=method, dim=d, key=sub, n_replicates=n_replicates
            )
        problems.append(
            {
                "title": title,
                "kind": kind,
                "dim": d,
                "a": a,
                "w": w,
                "f": f,
                "exact": exact,
                "studies": studies,
            }
        )
    return {"ns": ns, "n_replicates": n_replicates, "problems": problems}


@figure("fig_6_convergence")
def fig_6_convergence(out_dir, *, smoke: bool = False):
    """RMSE against n for several integrands and samplers on log-log axes (thesis ch. 6).

    Genz test integrands (smooth Gaussian and oscillatory, kinked continuous, discontinuous) in
    2-4 dimensions; plain MC, Latin hypercube, Owen-scrambled Halton and Owen-scrambled Sobol,
    each RMSE over independent replicates. The dotted guides have slopes -1/2 and -3/2. The
    data are `convergence_figure_data()`.
    """
    import matplotlib.pyplot as plt

    data = convergence_figure_data(smoke=smoke)
    ns = data["ns"]
    fig, axes = plt.subplots(1, len(_GENZ_PROBLEMS), figsize=(16.0, 4.0), layout="constrained")
    for ax, problem in zip(axes, data["problems"], strict=True):
        title = problem["title"]
        for method, label in _CONVERGENCE_METHODS:
            study = problem["studies"][method]
            ax.loglog(
                ns, np.asarray(study.rmse), "o-", ms=3, label=f"{label} ({float(study.slope):.2f})"
            )
        ref = np.asarray(ns, dtype=float)
        top = ax.get_ylim()[1] * 0.3
        ax.loglog(ref, top * (ref / ref[0]) ** -0.5, "k:", lw=0.8)
        ax.loglog(ref, top * (ref / ref[0]) ** -1.5, "k:", lw=0.8)
        ax.set_xscale("log", base=2)
        ax.set(title=title, xlabel="n", ylabel="RMSE")
        ax.legend(fontsize=7, title="fitted slope", title_fontsize=7)
    return save(fig, out_dir, "fig_6_convergence")


# A Lambertian point at the origin (normal +z) lit by a rectangular area light of radiance 1
# facing down at height H (thesis eq. 1.13: E = int L cos(theta) d omega).
_RECT = ((-0.3, 0.7), (0.2, 0.9))
_H = 1.0


def _rect_vertices():
    (x0, x1), (y0, y1) = _RECT
    return np.array([[x0, y0, _H], [x1, y0, _H], [x1, y1, _H], [x0, y1, _H]])


def rect_irradiance_exact() -> float:
    """Lambert's closed form for a polygon of unit radiance: E = 1/2 sum_i theta_i (n . u_i)."""
    v = _rect_vertices()
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    total = 0.0
    for i in range(4):
        a, b = v[i], v[(i + 1) % 4]
        c = np.cross(a, b)
        total += math.acos(np.clip(a @ b, -1, 1)) * c[2] / np.linalg.norm(c)
    return abs(0.5 * total)


def _rect_triangles():
    v = jnp.asarray(_rect_vertices())
    return [(v[0], v[1], v[2]), (v[0], v[2], v[3])]


def _rect_solid_angle():
    """The rectangle's solid angle seen from the origin [sr] (a JAX scalar: traceable)."""
    return sum(mc.spherical_triangle_area(*t) for t in _rect_triangles())


CONTROL_VARIATE = "light area + control variate"


def _rect_terms(method: str, n: int, key, *, cv_terms: bool = True):
    """Per-sample terms of the irradiance estimators (mean = E), shape (n,). For the control
    variate with `cv_terms=False`: its samples `(y, g)` (estimand and control), each (n,)."""
    (x0, x1), (y0, y1) = _RECT
    area = (x1 - x0) * (y1 - y0)

    def hits(w):
        t = _H / jnp.maximum(w[:, 2], 1e-12)
        px, py = t * w[:, 0], t * w[:, 1]
        inside = (w[:, 2] > 0) & (px >= x0) & (px <= x1) & (py >= y0) & (py <= y1)
        return inside, t

    def light_pdf_sa(w):  # area sampling density converted to solid angle: d^2 / (A cos_l)
        inside, t = hits(w)
        return jnp.where(inside, t**2 / (area * jnp.maximum(w[:, 2], 1e-12)), 0.0)

    def sample_light(u):
        p = jnp.stack(
            [x0 + u[:, 0] * (x1 - x0), y0 + u[:, 1] * (y1 - y0), jnp.full(u.shape[0], _H)], -1
        )
        return p / jnp.linalg.norm(p, axis=1, keepdims=True)

    def cos_pdf(w):
        return mc.cosine_hemisphere_pdf(w[:, 2])

    def f(w):  # L cos(theta) with L = 1 on the light
        return jnp.where(hits(w)[0], w[:, 2], 0.0)

    k1, k2 = jax.random.split(key)
    u = jax.random.uniform(k1, (n, 2))
    if method == "uniform hemisphere":
        w = mc.sample_uniform_hemisphere(u)
        return f(w) * 2 * math.pi
    if method == "cosine hemisphere":
        w = mc.sample_cosine_hemisphere(u)
        return f(w) / cos_pdf(w)
    if method == "light area":
        w = sample_light(u)
        return f(w) / light_pdf_sa(w)
    if method == "spherical triangles":
        tris = _rect_triangles()
        omegas = jnp.stack([mc.spherical_triangle_area(*t) for t in tris])
        idx, _, u0 = mc.sample_discrete(u[:, 0], omegas)
        uu = jnp.stack([u0, u[:, 1]], -1)
        w = jnp.where(
            (idx == 0)[:, None],
            mc.sample_spherical_triangle(uu, *tris[0]),
            mc.sample_spherical_triangle(uu, *tris[1]),
        )
        return w[:, 2] * jnp.sum(omegas)
    if method.startswith("MIS"):
        beta = 2.0 if "power" in method else 1.0
        wl = sample_light(u)
        wc = mc.sample_cosine_hemisphere(jax.random.uniform(k2, (n, 2)))
        pl = jnp.stack([light_pdf_sa(wl), cos_pdf(wl)], -1)
        pc = jnp.stack([light_pdf_sa(wc), cos_pdf(wc)], -1)
        tl = mc.mis_weights(pl, beta=beta)[:, 0] * f(wl) / pl[:, 0]
        okc = pc[:, 1] > 0
        tc = jnp.where(
            okc, mc.mis_weights(pc, beta=beta)[:, 1] * f(wc) / jnp.where(okc, pc[:, 1], 1.0), 0.0
        )
        return tl + tc  # one sample of each strategy per term
    if method == CONTROL_VARIATE:
        # Control G = A cos_l / d^2 on the same light samples; E[G] = solid angle of the light.
        w = sample_light(u)
        y = f(w) / light_pdf_sa(w)
        g = 1.0 / light_pdf_sa(w)
        return _control_variate_terms(y, g) if cv_terms else (y, g)
    raise ValueError(method)


def _control_variate_terms(y, g):
    """Terms whose mean is the control-variate estimate from these samples (`mc.control_variate`
    with the rectangle's solid angle as the control's mean, beta fitted on them)."""
    omega = _rect_solid_angle()
    est = mc.control_variate(y, g, omega)
    beta = (jnp.mean(y) - est.mean) / (jnp.mean(g) - omega)
    return y - beta * (g - omega)


# One compiled program per method (run op by op, the many small programs of the estimators
# held ~0.7 GB of compiled code and buffers; one per method and sample count took 19 s to
# compile in smoke mode).
_rect_terms_jit = jax.jit(_rect_terms, static_argnums=(0, 1))


@functools.partial(jax.jit, static_argnames=("method", "ns", "reps"))
def _rect_estimates(key, *, method: str, ns: tuple[int, ...], reps: int):
    """`(reps, len(ns))`: in each of `reps` independent replicates of `max(ns)` samples, the
    estimate of `method` from its first `n` samples, for each `n` of `ns` (the first `n` of
    i.i.d. samples are `n` i.i.d. samples; the control variate fits its beta on them).
    Replicates in batches of 32 (memory)."""

    def one(k):
        if method == CONTROL_VARIATE:
            y, g = _rect_terms(method, max(ns), k, cv_terms=False)
            return jnp.stack([_control_variate_terms(y[:n], g[:n]).mean() for n in ns])
        c = jnp.cumsum(_rect_terms(method, max(ns), k))
        return jnp.stack([c[n - 1] / n for n in ns])

    return jax.lax.map(one, jax.random.split(key, reps), batch_size=min(reps, 32))


RECT_METHODS = [
    "uniform hemisphere",
    "cosine hemisphere",
    "light area",
    "spherical triangles",
    "MIS balance (light + cosine)",
    "MIS power (light + cosine)",
    CONTROL_VARIATE,
]


def variance_reduction_data(*, smoke: bool = False) -> dict:
    """What fig. 7 (variance reduction) plots, for the irradiance under the rectangular light.

    `exact` = `rect_irradiance_exact()`; `methods` = `RECT_METHODS`; `ns`, the sample counts
    (4 ... 256 in smoke mode, else 4 ... 4096); `n_replicates` (32 or 256); `rmse` (methods,
    ns), the RMSE over independent replicates of the estimate from `n` samples (each
    replicate draws `max(ns)` samples; its estimate at `n` uses the first `n`); `n_var`
    (20 000 or 200 000) and `per_sample_var` (methods,), the variance of one term of each
    estimator (key 7, split in turn for every estimate).
    """
    exact = rect_irradiance_exact()
    ns = [4, 16, 64, 256] if smoke else [4, 16, 64, 256, 1024, 4096]
    reps = 32 if smoke else 256
    n_var = 20_000 if smoke else 200_000
    key = jax.random.key(7)
    rmse, per_sample_var = [], []
    for method in RECT_METHODS:
        key, sub = jax.random.split(key)
        ests = np.asarray(_rect_estimates(sub, method=method, ns=tuple(ns), reps=reps))
        rmse.append(np.sqrt(np.mean((ests - exact) ** 2, axis=0)))
        key, sub = jax.random.split(key)
        terms = _rect_terms_jit(method, n_var, sub)
        per_sample_var.append(float(np.var(np.asarray(terms))))
    return {
        "exact": exact,
        "methods": list(RECT_METHODS),
        "ns": ns,
        "n_replicates": reps,
        "rmse": np.array(rmse),
        "n_var": n_var,
        "per_sample_var": np.array(per_sample_var),
    }


@figure("fig_7_variance_reduction")
def fig_7_variance_reduction(out_dir, *, smoke: bool = False):
    """Variance of irradiance estimators for a rectangular area light (thesis eq. 1.13, ch. 7).

    A Lambertian point under a unit-radiance rectangle; the exact irradiance is Lambert's
    polygon formula. Left: RMSE against the number of samples for uniform and cosine hemisphere
    sampling, light-area sampling, uniform spherical-triangle (solid angle) sampling, MIS of
    light and cosine sampling (balance and power heuristics; each term uses one sample of
    each) and area sampling with a control variate (the light's solid angle). Right: the
    variance per sample. The data are `variance_reduction_data()`.
    """
    import matplotlib.pyplot as plt

    data = variance_reduction_data(smoke=smoke)
    exact, ns, per_sample_var = data["exact"], data["ns"], list(data["per_sample_var"])
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12.0, 4.2), layout="constrained")
    for method, rmse in zip(RECT_METHODS, data["rmse"], strict=True):
        ax0.loglog(ns, rmse, "o-", ms=3, label=method)
    ax0.set(
        xlabel="samples n",
        ylabel="RMSE of the irradiance",
        title=f"rectangular light, exact E = {exact:.5f} (eq. 1.13)",
    )
    ax0.legend(fontsize=7)
    y = np.arange(len(RECT_METHODS))
    ax1.barh(y, per_sample_var, color="tab:blue")
    ax1.set_yticks(y, RECT_METHODS, fontsize=8)
    ax1.set_xscale("log")
    ax1.invert_yaxis()
    ax1.set(xlabel="variance per sample", title="variance of one term")
    return save(fig, out_dir, "fig_7_variance_reduction")
