"""One's own model file, run by the command line: a compass gait whose leg masses sit nearer the hip.

The command line takes this file wherever it takes a library model's name:
``amble simulate examples/my_walker.py --steps 10``. It calls ``build()`` (or the callable named
after a colon, ``examples/my_walker.py:build``); a file without ``build()`` must define exactly
one ``HybridSystem`` at module level.

Run as a script, it simulates ten steps: ``python examples/my_walker.py``.
"""

from amble import Model, R, simulate, walker


def build():
    m = Model("my-walker")
    st, sw = m.coordinates("stance swing", unit="rad")
    mh, ml, a, b, g, slope = m.parameters(mh=10.0, m=5.0, a=0.4, b=0.6, g=9.81, slope=0.04)
    m.point("stance_foot", (0, 0))
    hip = m.point("hip", (a + b) * R(st), mass=mh, link="stance_foot")
    m.point("stance_mass", b * R(st), mass=ml)
    m.point("swing_mass", hip - a * R(sw), mass=ml)
    m.point("swing_foot", hip - (a + b) * R(sw), link="hip")
    m.gravity(g)
    return walker(m, foot="swing_foot", hip="hip", slope=slope, relabel={st: sw, sw: st},
                  start=[-0.19, 0.27, 1.0, 0.3], doc=__doc__)


if __name__ == "__main__":
    run = simulate(build(), steps=10)
    print(f"{run.status}: {run.steps} steps in {run.t[-1]:.3f} s")
