"""Figures and tables of the documentation, made from the package when the site is built.

``make docs`` calls :func:`generate` (through conf.py) before Sphinx reads the pages; the output
goes to docs/_generated/ (not committed): the contact-law curves (closed forms of the laws in
cpp/contact/, the same equations as the theory page), a sketch of the multi-level exchange
grid, the pushed layer's weight, and the scaling tables of grainscale.scaling.table.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import patches  # noqa: E402


def contact_laws(path: Path) -> None:
    """Hertz and the linear spring with the same maximum overlap; the EEPA branches."""
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    # sphere R = 1 mm, E = 1e7 Pa, nu = 0.3 on a rigid wall, impact speed 1 m/s
    r, e, nu, rho, v = 1e-3, 1e7, 0.3, 2500.0, 1.0
    e_eff, m = e / (1 - nu**2), rho * 4 / 3 * math.pi * r**3
    d_max = (15 * m * v**2 / (16 * e_eff * math.sqrt(r))) ** 0.4  # CASES.md A1
    k_lin = 16 / 15 * math.sqrt(r) * e_eff * (15 * m * v**2 / (16 * math.sqrt(r) * e_eff)) ** 0.2
    d = np.linspace(0, d_max, 200)
    a.plot(d * 1e6, 4 / 3 * e_eff * math.sqrt(r) * d**1.5, label="Hertz: 4/3 E* √R* δ^3/2")
    a.plot(d * 1e6, k_lin * d, "--", label="linear (Hooke, v_c = 1 m/s): k_n δ")
    a.set(xlabel="overlap δ (µm)", ylabel="elastic normal force (N)",
          title="Same maximum overlap at the impact speed")  # fmt: skip
    a.legend()
    # EEPA, n = 1, the path of CASES.md A7 with an adhesive branch and a pull-off offset
    k1, ratio, k_adh, f0 = 1.0, 3.0, 0.5, -0.05
    k2 = ratio * k1
    path_points = np.concatenate([np.linspace(0, 1, 60), np.linspace(1, 0.8, 20),
                                  np.linspace(0.8, 1.5, 60), np.linspace(1.5, 0, 120)])  # fmt: skip
    force, d_hist = [], 0.0
    for x in path_points:
        d_hist = max(d_hist, x)
        dp = (1 - k1 / k2) * d_hist
        # the branch logic of cpp/contact/normal_models.hpp (n = 1)
        force.append(f0 + max(min(k1 * x, k2 * (x - dp)), -k_adh * x))
    b.plot(path_points, force, color="C2")
    xs = np.linspace(0, 1.6, 50)
    b.plot(xs, f0 + k1 * xs, ":", color="grey", label="loading f0 + k1 δ")
    b.plot(xs, f0 - k_adh * xs, "-.", color="grey", label="adhesive f0 − k_adh δ")
    b.axhline(0, color="black", lw=0.5)
    b.set(xlabel="overlap δ / δ_max", ylabel="normal force (units of k1 δ_max)",
          title="EEPA branches (k2 = 3 k1), path of CASES.md A7")  # fmt: skip
    b.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def mlcg_sketch(path: Path) -> None:
    """A vertical section of a silo: coarse particles everywhere, a fine region at the orifice
    with its exchange cells (boundary and interior), interface faces and the pushed layer."""
    fig, ax = plt.subplots(figsize=(8, 6))
    rng = np.random.default_rng(3)
    width, height, cell = 12.0, 9.0, 1.5
    region = (3.0, 0.0, 9.0, 4.5)  # x0, y0, x1, y1: 4 x 3 cells, the floor is closed
    ax.add_patch(patches.Rectangle((0, 0), width, height, fill=False, lw=2))
    ax.plot([5.4, 6.6], [0, 0], color="white", lw=4)  # the orifice
    for i in range(4):
        for j in range(3):
            x, y = region[0] + i * cell, j * cell
            interior = 0 < i < 3 and j < 2
            ax.add_patch(patches.Rectangle((x, y), cell, cell, lw=0.8, ec="grey",
                                           fc="#dbe9f6" if interior else "#fde2c4"))  # fmt: skip
    for x, y in _scatter(rng, (0.5, 0.5, width - 0.5, 7.6), 0.45, 60):
        ax.add_patch(patches.Circle((x, y), 0.42, fc="none", ec="#1f4e9c", lw=1.2))
    inner = (region[0] + 0.12, 0.12, region[2] - 0.12, region[3] - 0.12)
    for x, y in _scatter(rng, inner, 0.105, 600):  # fine particles only inside the region
        ax.add_patch(patches.Circle((x, y), 0.1, fc="#c0392b", ec="none", alpha=0.8))
    layer = 0.26  # the pushed layer (1.3 fine diameters) along the interface faces
    for x0, y0, w, h in ((region[0], 0, layer, region[3]), (region[2] - layer, 0, layer, region[3]),
                         (region[0], region[3] - layer, region[2] - region[0], layer)):  # fmt: skip
        ax.add_patch(patches.Rectangle((x0, y0), w, h, fc="#7d3c98", alpha=0.45, ec="none"))
    style = {"arrowstyle": "->", "lw": 1.5}
    for x in (3.75, 5.25, 6.75, 8.25):
        ax.annotate("", (x, region[3] - 0.5), (x, region[3] + 0.5), arrowprops=style)
    notes = [
        (
            (9.3, 4.9),
            "interface face: the parent's crossings are booked,\n"
            "the child inserts in a shell just inside",
        ),
        (
            (9.3, 2.6),
            "boundary cells: velocity condition, shear\ntraction, stress push in a layer of 1.3 d",
        ),
        ((0.2, 8.2), "coarse level (h = 2): the whole silo"),
        ((4.6, 1.6), "interior cells:\nvelocity feedback\nfine → coarse"),
    ]
    for (x, y), text in notes:
        ax.text(x, y, text, fontsize=8.5, va="center",
                bbox={"fc": "white", "ec": "grey", "alpha": 0.9})  # fmt: skip
    ax.set(xlim=(-0.2, width + 0.2), ylim=(-0.6, height + 0.2), aspect="equal")
    ax.set_axis_off()
    ax.set_title("A fine region at a silo's orifice, its exchange cells and interface faces")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _scatter(rng: np.random.Generator, box: tuple, radius: float, n: int) -> list:
    """Up to n non-overlapping centres in box (x0, y0, x1, y1), random sequential addition."""
    points: list[tuple[float, float]] = []
    for _ in range(50 * n):
        p = (rng.uniform(box[0], box[2]), rng.uniform(box[1], box[3]))
        if all((p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 >= 4 * radius**2 for q in points):
            points.append(p)
            if len(points) == n:
                break
    return points


def layer_weight(path: Path, layer: float = 1.3, fade: float = 0.25) -> None:
    """The stress condition's push per particle against the distance from the face."""
    s = np.linspace(0, 1.6, 400)
    w = np.where(s <= layer - fade, 1.0, np.sin(0.5 * np.pi * (layer - s) / fade) ** 2)
    w[s >= layer] = 0.0
    fig, ax = plt.subplots(figsize=(6, 3))
    ax.plot(s, w)
    ax.axvline(layer - fade, ls=":", color="grey")
    ax.axvline(layer, ls=":", color="grey")
    ax.set(xlabel="distance from the interface face s (fine diameters)", ylabel="w(s)",
           title="F = p_f π r² w(s): the pushed layer and its sin² fade")  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def scaling_tables(path: Path) -> None:
    """Markdown tables of the factor exponents of every scheme (from the package's data)."""
    from grainscale.scaling import SCHEMES, factors, similarity_exponents

    lines = ["| quantity | " + " | ".join(f"{s} 3-D | {s} 2-D" for s in SCHEMES) + " |",
             "|---" * (1 + 2 * len(SCHEMES)) + "|"]  # fmt: skip
    tables = [factors(s, d) for s in SCHEMES for d in (3, 2)]
    for q in tables[0]:
        lines.append(f"| {q} | " + " | ".join(_power(t[q]) for t in tables) + " |")
    lines += ["", "| similarity number | " + " | ".join(f"{s} 3-D" for s in SCHEMES) + " |",
              "|---" * (1 + len(SCHEMES)) + "|"]  # fmt: skip
    numbers = [similarity_exponents(s, 3) for s in SCHEMES]
    for n in numbers[0]:
        lines.append(f"| {n} | " + " | ".join(_power(x[n]) for x in numbers) + " |")
    path.write_text("\n".join(lines) + "\n")


def _power(p: float) -> str:
    if p == 0:
        return "1"
    return "h" if p == 1 else f"h^{p:g}"


def generate(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    contact_laws(out / "contact_laws.png")
    mlcg_sketch(out / "mlcg_sketch.png")
    layer_weight(out / "layer_weight.png")
    scaling_tables(out / "scaling_tables.md")
