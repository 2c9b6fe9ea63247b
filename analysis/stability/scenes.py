"""The scenes of `make stability`: stiff and extreme cases, as text in the 2019 input format.

Pure functions: each scene is built from Python's seeded generator (random.Random is the same
on every platform), so the suite is reproducible without committed scene files. Scaled copies use
powers of two so that they are exact copies of their base scene.

Every scene says what it expects: `run` (exit 0 and every check) or `refuse` (exit 2 with a
message naming the reason), and the energy drift bound it can justify (see drift_bound()).
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

EPS = 2.0 ** -53  # unit roundoff of a double


@dataclass(frozen=True)
class Particle:
    x: float
    y: float
    vx: float
    vy: float


@dataclass
class Scene:
    name: str
    L: float
    r: float
    S: int
    particles: list[Particle] | None  # None: psim places them (random scene, header only)
    options: list[str] = field(default_factory=list)  # extra psim options (--slow-factor ...)
    refuse: str = ""  # when set, psim must exit 2 with a message containing this word
    refuse_by: dict[str, str] = field(default_factory=dict)  # the same, for one engine only
    # For one engine: it may either run (and pass every check) or exit 2 naming this word.
    may_refuse_by: dict[str, str] = field(default_factory=dict)
    quick: bool = False  # part of the quick subset that `make test` runs
    about: str = ""
    N: int = 0  # header N for a random scene

    def refusal(self, engine: str) -> str:
        """The word psim's refusal must contain for this engine; "" when it must run."""
        return self.refuse_by.get(engine, self.refuse)

    def slow_factor(self) -> int:
        if "--slow-factor" in self.options:
            return int(self.options[self.options.index("--slow-factor") + 1])
        return 1

    def text(self) -> str:
        n = self.N if self.particles is None else len(self.particles)
        lines = [str(n), repr(self.L), repr(self.r), str(self.S), "perf"]
        for i, p in enumerate(self.particles or []):
            lines.append(f"{i} {p.x!r} {p.y!r} {p.vx!r} {p.vy!r}")
        return "\n".join(lines) + "\n"


def drift_bound(pair_collisions: int) -> float:
    """Largest |E_final - E_initial| / E_initial that rounding can explain.

    Walls only flip signs (exact) and free motion does not touch velocities, so only pair
    collisions change the energy: one exchange along the unit normal changes the pair's energy
    by at most about 8 ulps of it (the normal, the projection and four updates), and the pair's
    energy is at most the total. Hence 8 eps per pair collision, summed; 1e-10 is the target
    whenever that sum is smaller.
    """
    return max(1e-10, 8 * EPS * pair_collisions)


def scaled(scene: Scene, name: str, length: float, velocity: float | None = None,
           **changes) -> Scene:
    """A copy of `scene` with lengths times `length` and velocities times `velocity`
    (default: the same factor, an exact scaled copy when both are powers of two)."""
    v = length if velocity is None else velocity
    parts = [Particle(p.x * length, p.y * length, p.vx * v, p.vy * v) for p in scene.particles]
    base = dict(name=name, L=scene.L * length, r=scene.r * length, S=scene.S, particles=parts,
                options=list(scene.options))
    base.update(changes)
    return Scene(**base)


def random_gas(rng: random.Random, n: int, L: float, r: float, speed: float) -> list[Particle]:
    """n non-overlapping particles uniform in the box, speeds uniform in [0, speed]."""
    out: list[Particle] = []
    s2 = (2 * r) ** 2
    while len(out) < n:
        x, y = rng.uniform(r, L - r), rng.uniform(r, L - r)
        if all((x - p.x) ** 2 + (y - p.y) ** 2 >= s2 for p in out):
            a, v = rng.uniform(0, 2 * math.pi), rng.uniform(0, speed)
            out.append(Particle(x, y, v * math.cos(a), v * math.sin(a)))
    return out


def hex_packing(rng: random.Random, rows: int, cols: int, r: float, fraction: float,
                speed: float) -> tuple[float, list[Particle]]:
    """A hexagonal packing at the given packing fraction (0.9069 is touching), small random
    velocities. Returns (L, particles); the box is as wide as the longer side of the lattice."""
    s = 2 * r
    a = s * math.sqrt(math.pi / (2 * math.sqrt(3)) / fraction)  # lattice spacing
    h = a * math.sqrt(3) / 2
    L = max(r + (cols - 1) * a + a / 2 + r, r + (rows - 1) * h + r) * (1 + 1e-9)
    parts = []
    for row in range(rows):
        for col in range(cols):
            x = r + col * a + (a / 2 if row % 2 else 0)
            y = r + row * h
            ang = rng.uniform(0, 2 * math.pi)
            parts.append(Particle(x, y, speed * math.cos(ang), speed * math.sin(ang)))
    return L, parts


def cradle(n: int, K: int) -> Scene:
    """A row of touching disks (exact: integer positions 2 apart) hit by one from the left."""
    parts = [Particle(1.0, 8.0, 3.0, 0.0)] + [Particle(8.0 + 2 * k, 8.0, 0.0, 0.0)
                                              for k in range(n)]
    return Scene(f"cradle_K{K}", 32.0, 1.0, 40, parts, ["--slow-factor", str(K)],
                 quick=K == 1, about="touching row, c = 0 exactly")


def squeezed(n: int, motion: str, axis: str, r: float = 3.0, gap: float = 0.25) -> Scene:
    """n overlapping disks in a row between wall lines 2r + gap apart, head-on (alternate
    directions) or chasing (one direction, different speeds), along x, y or the diagonal.

    Between walls that near, overlapping disks turned back by a wall collide again at once: in
    exact time their collisions can crowd towards an instant they never pass (issue 39's hang of
    the event engine). Every discrete engine must give brute's state; `event` must end, with a
    state or with exit 2 naming the time its collisions never pass.
    """
    L = 4 * r + gap
    lo, span = r, 2 * r + gap
    parts = []
    for k in range(n):
        at = lo + span * (k + 0.5) / n
        speed = 2.0 + k % 3
        v = speed * (-1) ** k if motion == "head_on" else speed
        x, y, vx, vy = {"x": (at, L / 2, v, 0.0), "y": (L / 2, at, 0.0, v),
                        "diag": (at, at, v, v)}[axis]
        parts.append(Particle(x, y, vx, vy))
    return Scene(f"squeezed_{n}_{motion}_{axis}", L, r, 12, parts,
                 may_refuse_by={"event": "never pass"}, quick=(n, motion) == (2, "head_on"),
                 about=f"{n} overlapping disks {motion.replace('_', '-')} along {axis} between "
                       f"wall lines 2r + {gap} apart")


def scenes() -> list[Scene]:
    rng = random.Random(8)
    base = Scene("base", 16.0, 1.0, 60, random_gas(rng, 8, 16.0, 1.0, 4.0), quick=True,
                 about="8 disks, L=16, r=1: the base of the scaled copies")
    L_hex, hexp = hex_packing(rng, 14, 14, 1.0, 0.85, 1e-3)
    ring = [Particle(16 + 6 * math.cos(2 * math.pi * k / 8), 16 + 6 * math.sin(2 * math.pi * k / 8),
                     -2 * math.cos(2 * math.pi * k / 8), -2 * math.sin(2 * math.pi * k / 8))
            for k in range(8)]
    out = [
        base,
        Scene("jammed_hex", L_hex, 1.0, 200, hexp, quick=True,
              about="hexagonal packing at fraction 0.85, speeds 1e-3"),
        cradle(6, 1),
        cradle(6, 1024),
        Scene("simultaneous_ring", 32.0, 1.0, 20, ring,
              about="8 disks converging on one point at the same time"),
        Scene("four_at_centre", 16.0, 1.0, 10,
              [Particle(4, 8, 1, 0), Particle(12, 8, -1, 0), Particle(8, 4, 0, 1),
               Particle(8, 12, 0, -1)], quick=True, about="four simultaneous head-ons"),
        Scene("exact_graze", 16.0, 1.0, 10,
              [Particle(2, 6, 1, 0), Particle(14, 8, -1, 0)],
              about="offset exactly s: disc == 0, a graze, no collision"),
        Scene("equal_velocities", 64.0, 1.0, 50,
              [Particle(p.x, p.y, 0.75, -0.5) for p in random_gas(rng, 30, 64.0, 1.0, 1.0)],
              about="w == 0 for every pair"),
        Scene("all_at_rest", 32.0, 1.0, 50,
              [Particle(p.x, p.y, 0.0, 0.0) for p in random_gas(rng, 30, 32.0, 1.0, 1.0)],
              quick=True, about="zero energy: drift defined as 0"),
        Scene("box_crosser", 64.0, 1.0, 50,
              [Particle(32, 32, 6400.5, 3200.25)]
              + [p for p in random_gas(rng, 40, 64.0, 1.0, 0.5)
                 if (p.x - 32) ** 2 + (p.y - 32) ** 2 >= 4],
              about="one particle crossing the box 100 times per step among slow ones"),
        Scene("L1e9_r1", 1e9, 1.0, 20, random_gas(rng, 50, 1e9, 1.0, 1e7),
              about="L/r = 1e9"),
        Scene("L1e9_r1e-3", 1e9, 1e-3, 20, random_gas(rng, 50, 1e9, 1e-3, 1e7),
              about="L/r = 1e12"),
        Scene("r1e-6_L1", 1.0, 1e-6, 20, random_gas(rng, 100, 1.0, 1e-6, 0.5),
              about="r = 1e-6 in L = 1"),
        scaled(base, "tiny_copy", 2.0 ** -668, quick=True,
               about="the base scene times 2^-668 (L = 1.0e-200)"),
        scaled(base, "huge_slow", 2.0 ** 993, 2.0 ** 500,
               about="base positions times 2^993 (L = 1.6e300), velocities times 2^500"),
        scaled(base, "huge_copy", 2.0 ** 993, refuse="energy",
               about="the base scene times 2^993: its kinetic energy is beyond a double"),
        Scene("tiny_random", 1e-200, 1e-201, 10, None, N=3, refuse="speed", quick=True,
              about="header only: the default speeds (up to L/(8r) = 1.25) are 6e200 s/step"),
        Scene("huge_random", 1e308, 1.0, 10, None, N=20, refuse="l/(2r)",
              about="header only: L/r = 1e308"),
        Scene("speeds_1e150", 1000.0, 1.0, 20,
              [Particle(100 + 200 * k, 500, (-1) ** k * 1e150, 1e149 * k) for k in range(4)],
              refuse_by={"event": "event engine"},
              about="speeds near 1e150 (within the 2^506 contact distances per step limit; "
                    "the event engine refuses 4e148 wall collisions)"),
        Scene("vx_1e300", 10.0, 1.0, 5, [Particle(5, 5, 1e300, 0)], refuse="speed",
              about="5e299 contact distances per step"),
        Scene("energy_1e300", 1e300, 1e299, 5, [Particle(5e299, 5e299, 1e300, 0)],
              refuse="energy", about="L/r = 10 but the kinetic energy overflows a double"),
        Scene("one_particle", 8.0, 1.0, 100, [Particle(3, 5, 1.5, -0.25)], quick=True,
              about="N = 1"),
        Scene("zero_steps", 16.0, 1.0, 0, base.particles, quick=True, about="S = 0"),
        Scene("walls_and_corners", 16.0, 1.0, 30,
              [Particle(1, 1, -1, -1), Particle(15, 15, 1, 1), Particle(1, 8, 1, 0),
               Particle(15, 5, -2, 0.5), Particle(8, 1, 0, -3), Particle(1, 15, -0.5, 0.5),
               Particle(15, 1, 0, 0)],
              quick=True, about="on wall lines and in corners, moving out and in"),
        Scene("long_run", 16.0, 1.0, 1000, base.particles[:4], ["--slow-factor", "1024"],
              about="a million sub-steps of 4 disks"),
        Scene("squeezed_fuzz_find", 12.0, 3.0, 30, [Particle(4, 5, 2, 0), Particle(3, 5, -3, 0)],
              may_refuse_by={"event": "never pass"}, quick=True,
              about="fuzz_scene's hang (issue 39): two disks of r = 3 overlapping between wall "
                    "lines 2r apart; exact time crowds towards t = 5"),
    ]
    out += [squeezed(n, motion, axis) for n in (2, 3, 5, 10) for motion in ("head_on", "chasing")
            for axis in ("x", "y", "diag")]
    return out
