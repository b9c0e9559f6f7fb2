"""Walkers whose stance feet are modes (left stance, right stance), written with the public API:
the compass gait as two modes, and RABBIT from its URDF rooted at either foot
(:func:`amble.stance_feet_walker`). Their gaits are those of the one-mode walkers that relabel
the legs at each footfall, which the tests compare them with."""

from pathlib import Path

from amble import Joint, Model, Walker, heel_strike, height_above_slope, stance_feet_walker
from amble.modelling.hybrid import Guard
from amble.models.compass_gait import model as compass_model

DATA = Path(__file__).parent / "data"


def compass_two_modes(slope: float = 0.05) -> Walker:
    """The compass gait with one mode per stance leg: ``left`` (the left leg is the stance leg)
    and ``right``, the same coordinates ``stance, swing`` in each; a footfall swaps the legs and
    the mode."""
    modes = {side: compass_model(f"compass-{side}", slope=slope) for side in ("left", "right")}
    w = Walker("compass-two-modes", modes, hip="hip", slope=modes["left"].symbol("slope"))
    for a, b in (("left", "right"), ("right", "left")):
        st, sw = modes[a].q
        guard, reset = heel_strike(modes[a], "swing_foot", modes[a].symbol("slope"), {st: sw, sw: st})
        w.transition(f"heel_strike_{b}", a, guard, reset, target=b, step=True)
    w.terminal("hip_on_ground", list(modes), lambda m: Guard(height_above_slope(m, "hip", m.symbol("slope")), -1),
               status="fell")
    w.default_start["left"] = [-0.2168, 0.3168, 1.0839, 0.3981]
    return w


def rabbit_stance(side: str) -> Model:
    """RABBIT's URDF rooted at its ``side`` foot, pivoting about ``y`` there (coordinate ``stance``,
    the foot's absolute angle), the four joints actuated (150 N·m)."""
    m = Model.from_urdf(DATA / "rabbit.urdf", name=f"rabbit_{side}", base=f"{side}_foot",
                        base_joint=Joint("revolute", axis=(0, 1, 0)), base_coordinate="stance")
    for q in m.q:
        if str(q) != "stance":
            m.actuator(f"u_{q}", on=q, limit=150.0)
    return m


def rabbit_two_modes() -> Walker:
    """RABBIT as a walker of two stance modes (``left``, ``right``) on level ground."""
    modes = {side: rabbit_stance(side) for side in ("left", "right")}
    return stance_feet_walker("rabbit-two-modes", modes, feet={"left": "left_foot", "right": "right_foot"},
                              hip="torso", max_step_time=2.0)


def compass_two_modes_hzd(slope: float = 0.05, degree: int = 4, shared: bool = True) -> Walker:
    """The two-mode compass gait with a hip motor (``u_hip`` on ``swing − stance``, 40 N·m) under
    hybrid zero dynamics in both modes: the output ``stance + swing`` (zero when the legs stand
    symmetric about the vertical) follows a Bézier polynomial in the phase ``stance``; the
    coefficients ``alpha_0_k`` are parameters shared by the two modes (``shared=False``: each
    mode its own, ``<mode>_alpha_0_k``), held at zero (legs symmetric) until a designed gait's are
    given."""
    w = compass_two_modes(slope)
    for m in w.modes.values():
        st, sw = m.q
        m.actuator("u_hip", on=sw - st, limit=40.0)
        m.virtual_constraints([st + sw], st, [[0.0] * (degree + 1)], (-0.2, 0.2), epsilon=0.05,
                              prefix="" if shared else f"{m.name.split('-')[-1]}_")
    return w
