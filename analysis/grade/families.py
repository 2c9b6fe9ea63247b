"""The families of judging scenes a grading draws from (draw.py; docs/programs.md, "Drawn judging
scenes"): one function per family, each drawing one scene that tests the rule its public example
in scenes/ tests, with new positions, speeds, box and radius, turned by a random symmetry of the
box and, where the rule allows, with its particles in a random index order.

Exactness: a tie is only a tie if the engine's arithmetic is exact on it. Every hand-made family
works with small dyadic numbers (halves and quarters, contact offsets that are integer vectors of
length 2r, contact times 1/4, 1/2, 3/4 of a step), so positions, wall times (L - r - x)/u and
pair roots c / (-b + sqrt(disc)) are exact: disc = (d_c . w)^2 is the square of a small dyadic
at a contact offset d_c of length 2r. A reflection x -> L - x of such numbers is exact too, and
`_Symmetry` refuses one that is not.

Each family returns a Drawn: the scene and its checks, each a claim about what psim does on the
scene (or on a variant of it, moved a hair so that the rule decides the other way: that is what
shows a tie is one) that draw.py verifies by running build/psim; a draw whose check fails is
drawn again. A family returns None where its numbers do not fit the box (drawn again at once).
`sim` is draw.py's Psim: final(scene, steps) and counters(scene) run psim, write_scene(header,
seed) draws psim's random scene.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Callable

Particle = tuple[float, float, float, float]  # x, y, vx, vy


@dataclass(frozen=True)
class Scene:
    """A print-mode scene in the 2019 input format, its particles in index order."""
    L: float
    r: float
    S: int
    particles: tuple[Particle, ...]

    def text(self, steps: int | None = None, mode: str = "print") -> str:
        """The scene as psim reads it (cut after `steps` time units, in `mode`, where given);
        repr is the shortest text of each double that reads back as the same double."""
        lines = [str(len(self.particles)), repr(float(self.L)), repr(float(self.r)),
                 str(self.S if steps is None else steps), mode]
        lines += [" ".join([str(i)] + [repr(float(v)) for v in p])
                  for i, p in enumerate(self.particles)]
        return "\n".join(lines) + "\n"

    def inside(self) -> bool:
        """Every particle in [r, L - r]^2, as psim requires."""
        return all(self.r <= c <= self.L - self.r for p in self.particles for c in p[:2])


def parse_scene(text: str) -> Scene:
    """A scene in the 2019 format with its particle lines (psim --write-scene's)."""
    lines = text.split("\n")
    n = int(lines[0])
    rows = sorted((int(f[0]), tuple(float(v) for v in f[1:5]))
                  for f in (line.split() for line in lines[5:5 + n]))
    return Scene(float(lines[1]), float(lines[2]), int(lines[3]), tuple(p for _, p in rows))


# A check: what psim must do on a scene, given draw.py's Psim; None when it does, else why not.
Check = Callable[[object], "str | None"]


@dataclass
class Drawn:
    scene: Scene
    checks: list[Check] = field(default_factory=list)


def counts(scene: Scene, step: int, expected: dict[int, tuple[int | None, int | None]],
           says: str) -> Check:
    """After `step` time units, particle i has the (pair, wall) collision counts expected[i]
    (None: any)."""
    def check(sim) -> str | None:
        final = sim.final(scene, step)
        for i, (pairs, walls) in expected.items():
            got = final[i][4:6]
            if (pairs is not None and got[0] != pairs) or (walls is not None and got[1] != walls):
                return (f"{says}: after time unit {step}, particle {i} has {got[0]} pair and "
                        f"{got[1]} wall collisions, expected {pairs} and {walls}")
        return None
    return check


def state(scene: Scene, step: int, i: int, expected: tuple[float | None, ...], says: str) -> Check:
    """After `step` time units, particle i is at (x, y, vx, vy) = expected (None: any), to the
    print's 8 decimals and the rounding of a normal's direction."""
    def check(sim) -> str | None:
        got = sim.final(scene, step)[i][:4]
        if any(e is not None and abs(g - e) > 1e-6 for g, e in zip(got, expected)):
            return f"{says}: after time unit {step}, particle {i} is {got}, expected {expected}"
        return None
    return check


def no_overlap(scene: Scene) -> Check:
    """No pair overlaps or touches at the start, in exact arithmetic (O(N^2): 20,000 pairs at
    N = 200, a tenth of a second)."""
    def check(_sim) -> str | None:
        s2 = (2 * Fraction(scene.r)) ** 2
        points = [(Fraction(p[0]), Fraction(p[1])) for p in scene.particles]
        for i, (xi, yi) in enumerate(points):
            for j in range(i + 1, len(points)):
                if (points[j][0] - xi) ** 2 + (points[j][1] - yi) ** 2 <= s2:
                    return f"particles {i} and {j} overlap at the start"
        return None
    return check


def at_least(scene: Scene, counter: str, least: int) -> Check:
    """psim's counter (--metrics) over the whole scene is at least `least`."""
    def check(sim) -> str | None:
        got = sim.counters(scene)[counter]
        return None if got >= least else f"{counter} {got}, fewer than {least}"
    return check


class _Symmetry:
    """One of the box's 8 symmetries (a swap of the axes, then a reflection of each), drawn at
    random; positions and velocities map exactly or the draw is refused (NotExact)."""

    def __init__(self, rng: random.Random):
        self.swap, self.flip_x, self.flip_y = (rng.random() < 0.5 for _ in range(3))

    def __call__(self, L: float, p: Particle) -> Particle:
        x, y, vx, vy = (p[1], p[0], p[3], p[2]) if self.swap else p
        if self.flip_x:
            x, vx = _reflected(L, x), -vx
        if self.flip_y:
            y, vy = _reflected(L, y), -vy
        return x, y, vx + 0.0, vy + 0.0  # + 0.0: no -0.0 in the scene's text


class NotExact(Exception):
    """A reflection L - x that rounds: the drawn scene would not be the one its checks assume."""


def _reflected(L: float, x: float) -> float:
    image = L - x
    if Fraction(image) != Fraction(L) - Fraction(x):
        raise NotExact(f"L - x rounds for L = {L!r}, x = {x!r}")
    return image


def _scene(L: float, r: float, S: int, roles: dict[str, Particle], order: list[str],
           turn: _Symmetry) -> Scene:
    """The particles of `roles`, turned by `turn`, indexed in `order` (role names)."""
    return Scene(L, r, S, tuple(turn(L, roles[name]) for name in order))


def _at(p_c: tuple[float, float], v: tuple[float, float], before: float) -> Particle:
    """A particle with velocity v that is at p_c `before` time units from now."""
    return p_c[0] - v[0] * before, p_c[1] - v[1] * before, v[0], v[1]


def _offsets(s: float) -> list[tuple[int, int]]:
    """The integer vectors of length s (a contact distance 2r): where a partner touches, so that
    the contact's arithmetic stays exact."""
    n = int(s)
    return [(a, b) for a in range(-n, n + 1) for b in range(-n, n + 1) if a * a + b * b == s * s]


def _dot(a, b) -> float:
    return a[0] * b[0] + a[1] * b[1]


def _half(rng: random.Random, low: int, high: int) -> float:
    """A multiple of 1/2 in [low, high]."""
    return rng.randint(2 * low, 2 * high) / 2


def _velocity(rng: random.Random, bound: int = 4) -> tuple[float, float]:
    return _half(rng, -bound, bound), _half(rng, -bound, bound)


def _line(L: float, r: float, v: float) -> float:
    """The wall line a particle moving at v heads for."""
    return L - r if v > 0 else r


RADII = (1.0, 2.5)   # contact distances 2 and 5: 4 and 12 exact contact offsets
TAUS = (0.25, 0.5, 0.75)
NUDGE = 2.0 ** -8    # a hair, in time or length: enough to break a tie, exact on these numbers


def corner(rng: random.Random, sim) -> Drawn | None:
    """A corner hit at exactly t = 1 of the first step: both components flip (taken in that step
    here; the check also accepts the next step's start). In the first step, because from a
    printed state the check cannot tell a corner from a hit a hair earlier on one axis: after one
    step a corner-as-one-wall program would be `ambiguous`, not caught."""
    L, r, k = rng.randint(8, 40), rng.choice((0.5, 1.0, 2.0)), 1
    room = L - 2 * r
    if room <= 2 * k:
        return None
    v = tuple(_half(rng, 1, math.floor(room / k - 0.5)) for _ in range(2))
    particle = (L - r - v[0] * k, L - r - v[1] * k, v[0], v[1])
    scene = _scene(L, r, k + 2, {"p": particle}, ["p"], _Symmetry(rng))
    x, y, vx, vy = scene.particles[0]
    return Drawn(scene, [counts(scene, k, {0: (0, 1)}, "the corner hit is in its step"),
                         state(scene, k, 0, (_line(L, r, vx), _line(L, r, vy), -vx, -vy),
                               "both components flip at the corner")])


def wall_before_end(rng: random.Random, sim) -> Drawn | None:
    """A wall hit a few ulps of a step before its end: the move overshoots the wall line by less
    than 1e-14, so a wall test with the 2019 code's tolerance misses it."""
    L, r = rng.randint(8, 30), rng.choice((0.5, 1.0))
    dist = _half(rng, 2, min(15, int(L - 2 * r) - 1))
    speed = dist + rng.randint(1, 4) * math.ulp(dist)
    y = _half(rng, math.ceil(r) + 1, math.floor(L - r) - 1)
    vy = rng.choice((0.0, 0.0, _half(rng, -1, 1)))
    particle = (L - r - dist, y, speed, vy)
    overshoot = Fraction(particle[0]) + Fraction(speed) - Fraction(L - r)
    if not 0 < overshoot < Fraction(1, 10 ** 14) or not r < y + vy < L - r:
        return None
    scene = _scene(L, r, 3, {"p": particle}, ["p"], _Symmetry(rng))
    p = scene.particles[0]
    flipped = tuple(-c if abs(c) == speed else c for c in p[2:])
    return Drawn(scene, [counts(scene, 1, {0: (0, 1)}, "the hit before the step's end is its"),
                         state(scene, 1, 0, (None, None, *flipped), "the hit flips the component")])


def _wall_beats_pair(rng: random.Random, high: bool) -> Drawn | None:
    """A hits the wall x = L - r at tau in step 1, exactly when it touches B: the wall wins, the
    pair is dropped. The variant, a box wider by a hair (A's hit a hair later), shows the tie:
    there the pair collides."""
    r = rng.choice(RADII)
    L, tau = rng.randint(24, 60), rng.choice(TAUS)  # 24: room for A's y with 8 either side
    v_a = (_half(rng, 1, 4), _half(rng, -2, 2))
    v_b = _velocity(rng)
    offset = rng.choice([o for o in _offsets(2 * r) if o[0] <= 0])
    if _dot((v_b[0] - v_a[0], v_b[1] - v_a[1]), offset) >= 0:
        return None
    y_a = rng.randint(math.ceil(r) + 8, math.floor(L - r) - 8)
    roles = {"A": _at((L - r, y_a), v_a, tau),
             "B": _at((L - r + offset[0], y_a + offset[1]), v_b, tau)}
    order = ["B", "A"] if high else ["A", "B"]
    a, b = order.index("A"), order.index("B")
    turn = _Symmetry(rng)
    scene, wider = (_scene(width, r, 1, roles, order, turn) for width in (L, L + NUDGE))
    # B hits no wall in the step: a wall of its own at the same time would drop the pair too,
    # and the variant, where every wall moves, would not tell.
    return Drawn(scene, [counts(scene, 1, {a: (0, 1), b: (0, 0)}, "the wall wins the tie"),
                         counts(wider, 1, {a: (1, 0), b: (1, 0)},
                                "with the wall a hair later the pair collides")])


def wall_beats_pair(rng: random.Random, sim) -> Drawn | None:
    """A wall hit and a pair collision at the same time, the wall on the lower index."""
    return _wall_beats_pair(rng, high=False)


def wall_beats_pair_high(rng: random.Random, sim) -> Drawn | None:
    """The same tie with the wall hit on the higher index (a tie by index alone takes the pair)."""
    return _wall_beats_pair(rng, high=True)


def three_in_row_tie(rng: random.Random, sim) -> Drawn | None:
    """A touches B and B touches C at the same time in the first step (from the scene's exact
    state: after a printed step the check would call a tie broken the other way ambiguous), the
    indices in a random order: the pair with the lower (i, j) collides, the other is dropped. The
    variant moves the loser's outer particle so that its contact comes a hair earlier: then that
    pair collides. The scene ends with that step: the dropped pair, passing through, would test
    the overlap rule next."""
    r = rng.choice(RADII)
    s = 2 * r
    offsets = _offsets(s)
    n1 = rng.choice(offsets)
    # A and C must not touch at the contact: |n1 + n2| > s
    n2 = rng.choice([o for o in offsets if _dot(n1, o) > -s * s / 2])
    k, tau = 1, rng.choice(TAUS)
    before = k - 1 + tau
    L = rng.randint(50, 100)
    centre = (rng.randint(20, L - 20), rng.randint(20, L - 20))
    v = {"A": _velocity(rng), "B": _velocity(rng, 2), "C": _velocity(rng)}
    if (_dot((v["B"][0] - v["A"][0], v["B"][1] - v["A"][1]), n1) >= 0
            or _dot((v["C"][0] - v["B"][0], v["C"][1] - v["B"][1]), n2) >= 0):
        return None
    where = {"A": (centre[0] - n1[0], centre[1] - n1[1]), "B": centre,
             "C": (centre[0] + n2[0], centre[1] + n2[1])}
    roles = {name: _at(where[name], v[name], before) for name in where}
    order = rng.sample(sorted(roles), 3)
    index = {name: order.index(name) for name in order}

    def key(p, q):
        return tuple(sorted((index[p], index[q])))
    winner, loser = ("A", "C") if key("A", "B") < key("B", "C") else ("C", "A")
    # the loser moved by NUDGE times its velocity relative to B: its contact NUDGE earlier
    x, y, vx, vy = roles[loser]
    nudged = dict(roles, **{loser: (x + NUDGE * (vx - v["B"][0]), y + NUDGE * (vy - v["B"][1]),
                                    vx, vy)})
    turn = _Symmetry(rng)
    scene, variant = (_scene(L, r, k, rs, order, turn) for rs in (roles, nudged))
    checks = [counts(scene, k, {index[winner]: (1, None), index["B"]: (1, None),
                                index[loser]: (0, None)}, "the lower indices win the tie"),
              counts(variant, k, {index[loser]: (1, None), index["B"]: (1, None),
                                  index[winner]: (0, None)},
                     "with the other contact a hair earlier, it collides")]
    return Drawn(scene, checks)


def _overlap(rng: random.Random, approaching: bool) -> Drawn | None:
    """Two particles overlapping at the start, moving together or apart."""
    r = rng.choice((1.0, 2.0, 2.5))
    s = 2 * r
    d = (rng.randint(-4 * int(s), 4 * int(s)) / 4, rng.randint(-4 * int(s), 4 * int(s)) / 4)
    v_a, v_b = _velocity(rng), _velocity(rng)
    b = _dot(d, (v_b[0] - v_a[0], v_b[1] - v_a[1]))
    if not 0 < _dot(d, d) < 0.8 * s * s or b == 0 or (b < 0) != approaching:
        return None
    L = rng.randint(20, 60)
    p = (rng.randint(10, L - 10), rng.randint(10, L - 10))
    roles = {"A": (*p, *v_a), "B": (p[0] + d[0], p[1] + d[1], *v_b)}
    scene = _scene(L, r, 1, roles, rng.sample(["A", "B"], 2), _Symmetry(rng))
    got = 1 if approaching else 0
    return Drawn(scene, [counts(scene, 1, {0: (got, 0), 1: (got, 0)},
                                "the overlapping pair " + ("collides at once" if approaching
                                                           else "is left alone"))])


def overlap_approaching(rng: random.Random, sim) -> Drawn | None:
    """An overlapping pair moving together collides at t = 0."""
    return _overlap(rng, approaching=True)


def overlap_receding(rng: random.Random, sim) -> Drawn | None:
    """An overlapping pair moving apart is left alone."""
    return _overlap(rng, approaching=False)


def _head_on(rng: random.Random):
    """A and B meeting head-on at tau of step k, both moving with a common velocity besides (a
    collision is head-on in the frame that moves with it): contact offset, velocities, time."""
    r = rng.choice(RADII)
    n = rng.choice(_offsets(2 * r))
    k, tau = rng.randint(1, 3), rng.choice(TAUS)
    common = _velocity(rng, 3)
    ka, kb = rng.randint(1, 4) / 4, rng.randint(1, 4) / 4
    v_a = (common[0] + ka * n[0], common[1] + ka * n[1])
    v_b = (common[0] - kb * n[0], common[1] - kb * n[1])
    return r, n, k, tau, v_a, v_b


def head_on(rng: random.Random, sim) -> Drawn | None:
    """A head-on pair collision in step k: velocities exchanged along the normal."""
    r, n, k, tau, v_a, v_b = _head_on(rng)
    L = rng.randint(40, 100)
    p = (rng.randint(15, L - 15), rng.randint(15, L - 15))
    roles = {"A": _at(p, v_a, k - 1 + tau), "B": _at((p[0] + n[0], p[1] + n[1]), v_b, k - 1 + tau)}
    order = rng.sample(["A", "B"], 2)
    scene = _scene(L, r, k + 1, roles, order, _Symmetry(rng))
    a, b = order.index("A"), order.index("B")
    va, vb = scene.particles[a][2:], scene.particles[b][2:]
    checks = [counts(scene, k, {a: (1, 0), b: (1, 0)}, "the pair collides in its step"),
              state(scene, k, a, (None, None, *vb), "the velocities are exchanged"),
              state(scene, k, b, (None, None, *va), "the velocities are exchanged")]
    if k > 1:
        checks.append(counts(scene, k - 1, {a: (0, 0), b: (0, 0)}, "nothing before"))
    return Drawn(scene, checks)


def three_at_once(rng: random.Random, sim) -> Drawn | None:
    """A and B meet head-on at tau in step k; C would touch A later in the same step, and its
    pair with A has the lower indices: by time A and B collide and C passes on (one collision per
    particle and step); by index, C would take A. The variant without B shows C's contact with A
    in that step."""
    r, n, k, tau, v_a, v_b = _head_on(rng)
    tau_c = rng.choice([t / 8 for t in range(1, 8) if t / 8 > tau])
    m = rng.choice([o for o in _offsets(2 * r) if o != n and o != (-n[0], -n[1])])
    v_c = _velocity(rng)
    if _dot((v_c[0] - v_a[0], v_c[1] - v_a[1]), m) >= 0:
        return None
    L = rng.randint(50, 100)
    p = (rng.randint(20, L - 20), rng.randint(20, L - 20))
    a_later = (p[0] + v_a[0] * (tau_c - tau), p[1] + v_a[1] * (tau_c - tau))
    before = k - 1 + tau
    roles = {"A": _at(p, v_a, before), "B": _at((p[0] + n[0], p[1] + n[1]), v_b, before),
             "C": _at((a_later[0] + m[0], a_later[1] + m[1]), v_c, k - 1 + tau_c)}
    order = rng.sample(sorted(roles), 3)
    index = {name: order.index(name) for name in order}
    if sorted((index["A"], index["C"])) > sorted((index["A"], index["B"])):
        return None
    turn = _Symmetry(rng)
    scene = _scene(L, r, k, roles, order, turn)
    pair = [name for name in order if name != "B"]
    without_b = _scene(L, r, k, roles, pair, turn)
    checks = [counts(scene, k, {index["A"]: (1, None), index["B"]: (1, None),
                                index["C"]: (0, None)}, "the earliest pair collides"),
              counts(without_b, k, {pair.index("A"): (1, None), pair.index("C"): (1, None)},
                     "without B, C collides with A in that step")]
    if k > 1:
        checks.append(counts(scene, k - 1, {i: (0, 0) for i in range(3)}, "nothing before"))
    return Drawn(scene, checks)


def cradle(rng: random.Random, sim) -> Drawn | None:
    """Newton's cradle: a striker touches the first of a row of 3 touching balls at exactly the
    end of step k, at 2r per time unit along the row: the first ball collides in step k, the
    second in step k + 1 (at t = 0, touching), never two in one step; the second then passes the
    third, ending touching it from the far side, moving away (with 2 balls a program that takes
    two collisions a step is not caught; a fourth would sit where the second ends)."""
    r = rng.choice(RADII)
    n = rng.choice(_offsets(2 * r))
    balls, k = 3, rng.randint(1, 3)
    L = rng.randint(60, 120)
    start = (rng.randint(10, L - 10), rng.randint(10, L - 10))
    v = (2 * n[0], 2 * n[1])
    roles = {"striker": _at((start[0] - n[0], start[1] - n[1]), v, k)}
    for j in range(balls):
        roles[f"ball{j + 1}"] = (start[0] + j * n[0], start[1] + j * n[1], 0.0, 0.0)
    order = rng.sample(sorted(roles), len(roles))
    index = {name: order.index(name) for name in order}
    scene = _scene(L, r, k + 2, roles, order, _Symmetry(rng))
    rest = {index[f"ball{j}"]: (0, 0) for j in range(3, balls + 1)}
    return Drawn(scene, [
        counts(scene, k, {index["striker"]: (1, 0), index["ball1"]: (1, 0),
                          index["ball2"]: (0, 0), **rest}, "the striker hits the first ball"),
        counts(scene, k + 1, {index["striker"]: (1, 0), index["ball1"]: (2, 0),
                              index["ball2"]: (1, 0), **rest}, "the pulse takes a step per ball"),
        counts(scene, k + 2, {index["ball2"]: (1, 0), **rest}, "no collision with the row's end")])


def faster_than_box(rng: random.Random, sim) -> Drawn | None:
    """A particle crossing the box in less than a step: after its hit it stops on the other wall
    line, and its next hit is in the next step."""
    L, r = rng.randint(6, 30), rng.choice((0.5, 1.0, 2.0))
    if L - 2 * r < 2:
        return None
    x = _half(rng, math.ceil(r), math.floor(L - r))
    y = _half(rng, math.ceil(r), math.floor(L - r))
    speed = (L - r - x) + (L - 2 * r) + _half(rng, 1, 20)
    scene = _scene(L, r, 2, {"p": (x, y, speed, 0.0)}, ["p"], _Symmetry(rng))
    p = scene.particles[0]
    back = (-p[2], -p[3])
    return Drawn(scene, [
        counts(scene, 1, {0: (0, 1)}, "one hit in the first step"),
        state(scene, 1, 0, (_line(L, r, back[0]) if back[0] else p[0],
                            _line(L, r, back[1]) if back[1] else p[1], *back),
              "stopped on the other wall line"),
        counts(scene, 2, {0: (0, 2)}, "the next hit in the next step"),
        state(scene, 2, 0, (_line(L, r, p[2]) if p[2] else p[0],
                            _line(L, r, p[3]) if p[3] else p[1], p[2], p[3]),
              "stopped on the first wall line")])


def _psim_random(sim, rng: random.Random, header: str, least: dict[str, int]) -> Drawn:
    scene = parse_scene(sim.write_scene(header, rng.getrandbits(64)))
    return Drawn(scene, [no_overlap(scene)]
                 + [at_least(scene, counter, n) for counter, n in least.items()])


def random_bulk(rng: random.Random, sim) -> Drawn | None:
    """200 random particles in a box of 20000, 50 time units (psim's random scene, a fresh seed):
    every rule in bulk, every printed value in %.8f."""
    return _psim_random(sim, rng, "200\n20000\n1\n50\nprint\n",
                        {"pair_collisions": 5, "wall_collisions": 1000})


def dense(rng: random.Random, sim) -> Drawn | None:
    """200 particles in a box of 400, 300 time units (psim's random scene, a fresh seed): no pair
    overlapping at the start, thousands of pair collisions, many near-ties and grazes."""
    return _psim_random(sim, rng, "200\n400\n1\n300\nprint\n", {"pair_collisions": 5000})


FAMILIES: dict[str, Callable[[random.Random, object], Drawn | None]] = {
    "corner": corner, "wall_before_end": wall_before_end, "wall_beats_pair": wall_beats_pair,
    "wall_beats_pair_high": wall_beats_pair_high, "three_in_row_tie": three_in_row_tie,
    "overlap_approaching": overlap_approaching, "overlap_receding": overlap_receding,
    "head_on": head_on, "three_at_once": three_at_once, "cradle": cradle,
    "faster_than_box": faster_than_box, "random": random_bulk, "dense": dense,
}
