"""A URDF's ``<dynamics damping>`` as the generalised force ``−d q̇``: against Pinocchio's forward
dynamics with the torque ``−d v`` (it reads the same file's damping), and against the energy law
``dE/dt = −Σ d q̇²`` along a run. Friction and ``<transmission>`` are ignored with a warning."""

import warnings

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

from amble import HybridSystem, Model, simulate
from amble.backend.kernels import build
from amble.errors import ModelError

pin = pytest.importorskip("pinocchio", reason="Pinocchio (pip install pin) is the reference; not installed")

_LINK = ('<link name="{n}"><inertial><origin xyz="{c}" rpy="0.1 -0.2 0.3"/><mass value="{m}"/>'
         '<inertia ixx="0.02" ixy="0.001" ixz="-0.002" iyy="0.018" iyz="0.0015" izz="0.006"/></inertial></link>')
_JOINT = ('<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{c}"/>'
          '<origin xyz="{o}" rpy="0.2 0 -0.1"/><axis xyz="{a}"/><limit lower="-2" upper="2" effort="10" velocity="5"/>'
          '{d}</joint>')


def _urdf(tmp_path, friction: float = 0.0, transmission: bool = False):
    links = "".join(_LINK.format(n=n, c=c, m=m) for n, c, m in
                    (("base", "0 0 0", 1), ("upper", "0.02 0 -0.2", 1.5), ("lower", "0 0.01 -0.15", 0.8)))
    joints = (_JOINT.format(n="hip", p="base", c="upper", o="0 0 0", a="0 1 0",
                            d=f'<dynamics damping="0.4" friction="{friction}"/>')
              + _JOINT.format(n="knee", p="upper", c="lower", o="0.01 0 -0.4", a="0.2 1 0",
                              d='<dynamics damping="0.15"/>'))
    extra = ('<transmission name="t"><type>transmission_interface/SimpleTransmission</type>'
             '<joint name="hip"/></transmission>') if transmission else ""
    path = tmp_path / "damped.urdf"
    path.write_text(f'<robot name="damped">{links}{joints}{extra}</robot>')
    return path


def test_damping_matches_pinocchio_forward_dynamics(tmp_path):
    path = _urdf(tmp_path)
    model = Model.from_urdf(path)
    k = build(HybridSystem(model.name, model))
    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    assert list(pm.damping) == [0.4, 0.15]
    rng = np.random.default_rng(2)
    for _ in range(20):
        q, v = rng.uniform(-1.5, 1.5, 2), rng.uniform(-3, 3, 2)
        qdd = k.rhs(0, 0.0, np.concatenate([q, v]), np.zeros(1))[2:]
        ref = pin.aba(pm, pd, q, v, -pm.damping * v)
        assert np.abs(qdd - ref).max() <= 1e-12 * np.abs(ref).max()


def test_a_damped_chain_loses_energy_at_the_rate_d_qdot_squared(tmp_path):
    model = Model.from_urdf(_urdf(tmp_path))
    tr = simulate(HybridSystem(model.name, model), [0.5, -0.4, 1.5, -2.0], t_end=1.0, sample_dt=0.001,
                  rtol=1e-12, atol=1e-12)
    e = tr.energy().sum(axis=1)
    power = -0.4 * tr.column("hip_dot") ** 2 - 0.15 * tr.column("knee_dot") ** 2
    lost = cumulative_simpson(power, x=tr.t, initial=0.0)
    assert e[0] - e[-1] > 0.1
    assert np.max(np.abs((e - e[0]) - lost)) < 1e-8 * (e[0] - e[-1])


def test_friction_and_transmissions_are_ignored_with_a_warning(tmp_path):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        Model.from_urdf(_urdf(tmp_path, friction=0.2, transmission=True))
    text = " ".join(str(x.message) for x in w)
    assert "joint friction (hip)" in text and "1 <transmission>" in text


def test_negative_damping_is_refused(tmp_path):
    path = _urdf(tmp_path)
    path.write_text(path.read_text().replace('damping="0.4"', 'damping="-0.4"'))
    with pytest.raises(ModelError, match="damping -0.4 must be finite and non-negative"):
        Model.from_urdf(path)
