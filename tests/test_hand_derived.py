"""Hand-derived cases: every expected number below is worked out in the comments.

Rotations used (columns = body axes in world):
    Rz(90°) = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]   (x, y, z) -> (-y, x, z)
    Rx(90°) = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]   (x, y, z) -> (x, -z, y)
"""

from __future__ import annotations

import numpy as np
import pytest

import mbody
from mbody.model import State

S2 = np.sqrt(0.5)
RZ90 = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
RX90 = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
Q_RZ90 = [S2, 0.0, 0.0, S2]
Q_RX90 = [S2, S2, 0.0, 0.0]
TIGHT = {"rtol": 0, "atol": 1e-12}


def close(a, b, atol=1e-12):
    np.testing.assert_allclose(np.asarray(a, float), np.asarray(b, float), rtol=0, atol=atol)


def rows(asm, vec, body):
    """The rows of stacked vector `vec` that belong to `body`."""
    k = 3 if asm.model.dimension == 2 else 6
    i = asm.model.body_names.index(body)
    return np.asarray(vec)[k * i:k * i + k]


def forces_named(asm, body, name):
    return [f for f in asm.bodies[body].fbd.forces if f.name == name]


# -- moment of an offset force ------------------------------------------------------------

def test_offset_force_planar_rotated_body():
    """θ = 90°; F = (3, 4) world at body point (0.5, 0) -> world arm R r = (0, 0.5);
    M = r × F = 0·4 − 0.5·3 = −1.5.  m = 2, I_G = 0.5: a = (1.5, 2), α = −3."""
    spec = {"dimension": 2, "bodies": [
        {"name": "p", "mass": 2.0, "inertia": 0.5, "position": [1.0, 1.0], "angle": "90 deg"}],
        "loads": [{"name": "F", "type": "force", "body": "p", "force": [3.0, 4.0],
                   "at": [0.5, 0.0]}]}
    asm = mbody.assemble(mbody.load(spec))
    close(asm.Q, [3.0, 4.0, -1.5])
    close(asm.solve().accelerations, [1.5, 2.0, -3.0])
    (f,) = forces_named(asm, "p", "F")
    close(f.B_moment, [0, 0, -1.5])
    close(f.W_point, [1.0, 1.5, 0.0])
    close(f.B_r, [0.5, 0.0, 0.0])
    assert f.kind == "applied" and not f.couple


def test_offset_force_spatial_rotated_body():
    """Rz(90°); F = (0, 0, 10) world at body point r = (1, 0, 0).
    Body axes: Rᵀ F = (0, 0, 10); r × RᵀF = (0·10 − 0·0, 0·0 − 1·10, 0) = (0, −10, 0).
    (World check: R r = (0, 1, 0); (0, 1, 0) × (0, 0, 10) = (10, 0, 0) = R (0, −10, 0).)"""
    spec = {"dimension": 3, "bodies": [
        {"name": "b", "mass": 5.0, "inertia": [1.0, 2.0, 2.5],
         "orientation": {"quaternion": Q_RZ90}}],
        "loads": [{"name": "F", "type": "force", "body": "b", "force": [0.0, 0.0, 10.0],
                   "at": [1.0, 0.0, 0.0]}]}
    asm = mbody.assemble(mbody.load(spec))
    close(asm.Q, [0, 0, 10, 0, -10, 0])
    close(asm.solve().accelerations, [0, 0, 2.0, 0, -5.0, 0])
    (f,) = forces_named(asm, "b", "F")
    close(f.B_moment, [0, -10, 0])
    close(f.W_point, [0, 1, 0])
    close(RZ90 @ f.B_moment, np.cross(f.W_point, f.W_vector))


# -- world- versus body-frame loads -------------------------------------------------------

def test_world_versus_body_frame_spatial():
    """Rx(90°).  Body force (0, 5, 0) -> world R(0, 5, 0) = (0, 0, 5).
    World force (0, 5, 0) stays (0, 5, 0).  Body couple (0, 0, 2) stays (0, 0, 2) in body
    axes; world couple (0, 0, 2) -> body Rᵀ(0, 0, 2) = (0, 2, 0)."""
    def model(frame):
        return {"dimension": 3, "bodies": [
            {"name": "b", "mass": 1.0, "inertia": [1.0, 1.0, 1.0],
             "orientation": {"quaternion": Q_RX90}}],
            "loads": [{"type": "force", "body": "b", "force": [0, 5.0, 0], "frame": frame},
                      {"type": "torque", "body": "b", "torque": [0, 0, 2.0], "frame": frame}]}
    body = mbody.assemble(mbody.load(model("body")))
    world = mbody.assemble(mbody.load(model("world")))
    close(body.Q, [0, 0, 5, 0, 0, 2])
    close(world.Q, [0, 5, 0, 0, 2, 0])


def test_world_versus_body_frame_planar_with_offset():
    """θ = 90°, force (10, 0) at body point (0, 1) (world arm R r = (−1, 0)).
    Body frame: world force R(10, 0) = (0, 10); M = (−1)(10) − 0·0 = −10.
    World frame: (10, 0); M = (−1)(0) − 0·10 = 0."""
    def model(frame):
        return {"dimension": 2, "bodies": [
            {"name": "p", "mass": 1.0, "inertia": 1.0, "angle": np.pi / 2}],
            "loads": [{"type": "force", "body": "p", "force": [10.0, 0], "at": [0, 1.0],
                       "frame": frame}]}
    close(mbody.assemble(mbody.load(model("body"))).Q, [0, 10, -10])
    close(mbody.assemble(mbody.load(model("world"))).Q, [10, 0, 0])


def test_body_frame_load_follows_the_body_at_any_state():
    """assemble(model, state): a body-frame force turns with the body, a world one not."""
    spec = {"dimension": 3, "bodies": [{"name": "b", "mass": 1.0, "inertia": [1, 1, 1]}],
            "loads": [{"name": "fb", "type": "force", "body": "b", "force": [1.0, 0, 0],
                       "frame": "body"},
                      {"name": "fw", "type": "force", "body": "b", "force": [0, 0, 1.0]}]}
    model = mbody.load(spec)
    state = State(np.zeros((1, 3)), np.array([Q_RZ90]), np.zeros((1, 3)), np.zeros((1, 3)))
    # body x turned by Rz(90°) is world y
    close(mbody.assemble(model, state).Q[:3], [0, 1, 1])
    close(mbody.assemble(model).Q[:3], [1, 0, 1])


# -- full inertia tensor in a rotated body ------------------------------------------------

J_FULL = [[3.0, -0.5, 0.2], [-0.5, 4.0, 0.1], [0.2, 0.1, 5.0]]


def test_full_inertia_rotated_body_euler_equation():
    """ω = (1, −2, 0.5) body axes.  Jω = (3 + 1 + 0.1, −0.5 − 8 + 0.05, 0.2 − 0.2 + 2.5)
    = (4.1, −8.45, 2.5);  ω × Jω = ((−2)(2.5) − (0.5)(−8.45), (0.5)(4.1) − (1)(2.5),
    (1)(−8.45) − (−2)(4.1)) = (−0.775, −0.45, −0.25).
    Orientation Rx(90°); couples (1, 0, 0) body and (0, 0, 2) world -> body (0, 2, 0):
    M = (1, 2, 0);  ω̇ = J⁻¹ (M − ω × Jω) = J⁻¹ (1.775, 2.45, 0.25)."""
    spec = {"dimension": 3, "bodies": [
        {"name": "b", "mass": 2.0, "inertia": J_FULL, "angular_velocity": [1.0, -2.0, 0.5],
         "orientation": {"matrix": RX90.tolist()}}],
        "loads": [{"type": "torque", "body": "b", "torque": [1.0, 0, 0], "frame": "body"},
                  {"type": "torque", "body": "b", "torque": [0, 0, 2.0], "frame": "world"}]}
    asm = mbody.assemble(mbody.load(spec))
    close(asm.b, [0, 0, 0, -0.775, -0.45, -0.25])
    close(asm.Q, [0, 0, 0, 1, 2, 0])
    close(asm.M.toarray()[3:, 3:], J_FULL)
    wdot = np.linalg.solve(J_FULL, [1.775, 2.45, 0.25])
    close(asm.solve().accelerations, [0, 0, 0, *wdot])
    # the rotated pose must not leak into the body-axis Euler equation
    eq = asm.bodies["b"].euler[0]
    assert eq.lhs == {"alpha_1": 3.0, "alpha_2": -0.5, "alpha_3": 0.2}
    assert eq.gyro == pytest.approx(-0.775, abs=1e-12)


def test_full_tensor_equals_principal_body_in_other_axes():
    """One physical body described twice: A with principal axes (2, 3, 4) at pose R_A;
    B with body axes turned by S relative to A: J_B = S J_A Sᵀ, R_B = R_A Sᵀ, ω_B = S ω_A,
    r_B = S r_A.  Same world loads -> same a_G, and ω̇_B = S ω̇_A."""
    from scipy.spatial.transform import Rotation

    S = Rotation.from_euler("xyz", [0.4, -0.7, 1.1]).as_matrix()
    R_A = Rotation.from_euler("ZYX", [0.3, 0.2, -0.5]).as_matrix()
    JA = np.diag([2.0, 3.0, 4.0])
    wA, rA = np.array([0.7, -1.2, 2.0]), np.array([0.3, -0.1, 0.2])
    F, tau, g = [1.0, -2.0, 3.0], [0.5, 0.25, -1.0], [0.0, 0.0, -9.81]

    def spec(J, R, w, r):
        return {"dimension": 3, "gravity": g, "bodies": [
            {"name": "b", "mass": 3.0, "inertia": np.asarray(J).tolist(),
             "orientation": {"matrix": np.asarray(R).tolist()},
             "angular_velocity": np.asarray(w).tolist()}],
            "loads": [{"type": "force", "body": "b", "force": F, "at": np.asarray(r).tolist()},
                      {"type": "torque", "body": "b", "torque": tau}]}
    a = mbody.assemble(mbody.load(spec([2.0, 3.0, 4.0], R_A, wA, rA))).solve().accelerations
    b = mbody.assemble(mbody.load(spec(S @ JA @ S.T, R_A @ S.T, S @ wA, S @ rA))
                       ).solve().accelerations
    close(b[:3], a[:3], 1e-12)
    close(b[3:], S @ a[3:], 1e-12)
    assert np.linalg.norm(a[3:]) > 1.0  # not a trivial case


# -- planar model = the same motion written as a spatial model -----------------------------

def _planar_and_spatial():
    bodies2 = [
        {"name": "arm", "mass": 2.0, "inertia": 0.5, "position": [0.5, 0.2], "angle": 0.4,
         "velocity": [0.3, -0.2], "angular_velocity": 1.5},
        {"name": "slider", "mass": 1.5, "inertia": 0.2, "position": [1.5, -0.3],
         "angle": -0.7, "velocity": [-0.1, 0.4], "angular_velocity": -0.8},
        {"name": "plate", "mass": 3.0, "inertia": 0.9, "position": [-1.0, 0.8], "angle": 2.0,
         "velocity": [0.2, 0.1], "angular_velocity": 0.3},
    ]
    loads2 = [
        {"name": "fw", "type": "force", "body": "arm", "force": [3.0, -1.0], "at": [0.2, 0.1]},
        {"name": "fb", "type": "force", "body": "slider", "force": [-2.0, 4.0],
         "at": [-0.1, 0.3], "frame": "body"},
        {"name": "tq", "type": "torque", "body": "plate", "torque": 1.5},
        {"name": "k1", "type": "spring", "bodies": ["ground", "arm"], "at": [[0, 1.0], [0.3, 0]],
         "stiffness": 50.0, "rest_length": 0.4, "damping": 2.0},
        {"name": "k2", "type": "spring", "bodies": ["slider", "plate"],
         "at": [[0.1, 0.1], [0.2, -0.2]], "stiffness": 20.0, "rest_length": 1.0, "damping": 1.0},
    ]
    s = np.hypot(0.6, 0.8)
    joints2 = [
        {"name": "A", "type": "revolute", "parent": "ground", "child": "arm", "at": [0.1, 0.0]},
        {"name": "B", "type": "prismatic", "parent": "arm", "child": "slider",
         "at": [1.2, -0.1], "axis": [0.6 / s, 0.8 / s]},
        {"name": "C", "type": "fixed", "parent": "slider", "child": "plate", "at": [0.0, 0.5]},
    ]
    known2 = {"A.Fx": 2.0, "A.Fy": -3.0, "B.Fy": 1.5, "B.Mz": -0.7,
              "C.Fx": 0.4, "C.Fy": 0.9, "C.Mz": 0.25}
    planar = {"dimension": 2, "gravity": [0.0, -9.81], "bodies": bodies2, "loads": loads2,
              "joints": joints2, "reactions": known2}

    def v3(v):
        return [*v, 0.0]
    bodies3 = []
    for b in bodies2:
        I = b["inertia"]
        bodies3.append({"name": b["name"], "mass": b["mass"], "inertia": [0.6 * I, 0.7 * I, I],
                        "position": v3(b["position"]), "velocity": v3(b["velocity"]),
                        "orientation": {"euler": [b["angle"], 0, 0], "sequence": "ZYX"},
                        "angular_velocity": [0.0, 0.0, b["angular_velocity"]]})
    loads3 = []
    for ld in loads2:
        ld = dict(ld)
        if ld["type"] == "force":
            ld["force"], ld["at"] = v3(ld["force"]), v3(ld["at"])
        elif ld["type"] == "torque":
            ld["torque"] = [0.0, 0.0, ld["torque"]]
        else:
            ld["at"] = [v3(p) for p in ld["at"]]
        loads3.append(ld)
    joints3 = []
    for j in joints2:
        j = dict(j, at=v3(j["at"]))
        if "axis" in j:
            j["axis"] = v3(j["axis"])
        elif j["type"] == "revolute":
            j["axis"] = [0.0, 0.0, 1.0]
        joints3.append(j)
    # Spatial frames by the contract: revolute about z and fixed with no axis -> world axes;
    # prismatic along (a, b, 0): z = axis, x = world z (least aligned), y = z × x = (b, −a, 0)
    # = −(planar y).  So planar B.Fy = −spatial B.Fy and planar B.Mz = spatial B.Mx.
    known3 = {"A.Fx": 2.0, "A.Fy": -3.0, "A.Fz": 0.0, "A.Mx": 0.0, "A.My": 0.0,
              "B.Fx": 0.0, "B.Fy": -1.5, "B.Mx": -0.7, "B.My": 0.0, "B.Mz": 0.0,
              "C.Fx": 0.4, "C.Fy": 0.9, "C.Fz": 0.0, "C.Mx": 0.0, "C.My": 0.0, "C.Mz": 0.25}
    spatial = {"dimension": 3, "gravity": [0.0, -9.81, 0.0], "bodies": bodies3,
               "loads": loads3, "joints": joints3, "reactions": known3}
    return planar, spatial


def test_planar_and_spatial_give_the_same_accelerations():
    planar, spatial = _planar_and_spatial()
    a2 = mbody.assemble(mbody.load(planar))
    a3 = mbody.assemble(mbody.load(spatial))
    acc2 = a2.solve().accelerations.reshape(-1, 3)
    acc3 = a3.solve().accelerations.reshape(-1, 6)
    close(acc3[:, [0, 1, 5]], acc2, 1e-11)
    close(acc3[:, 2:5], np.zeros((3, 3)), 1e-11)
    close(a3.Q.reshape(-1, 6)[:, [0, 1, 5]], a2.Q.reshape(-1, 3), 1e-11)
    close(a3.b, np.zeros(18))
    # the prismatic joint's frame: spatial y = −(planar y), spatial x = world z
    G2, G3 = a2.G.toarray(), a3.G.toarray()
    keep = np.array([6 * i + k for i in range(3) for k in (0, 1, 5)])
    col2, col3 = a2.reactions.index, a3.reactions.index
    close(G3[keep, col3("B.Fy")], -G2[:, col2("B.Fy")])
    close(G3[keep, col3("B.Mx")], G2[:, col2("B.Mz")])
    close(G3[keep, col3("A.Fx")], G2[:, col2("A.Fx")])
    assert np.abs(acc2).max() > 1.0


# -- springs with damping -----------------------------------------------------------------

def test_spring_damper_between_two_spatial_bodies():
    """a at origin (identity), end r_a = (0, 1, 0) -> P_a = (0, 1, 0).
    b at (3, 0, 0), Rz(90°), end r_b = (1, 0, 0) -> R r_b = (0, 1, 0), P_b = (3, 1, 0).
    L = 3, u = (P_b − P_a)/L = (1, 0, 0).  k = 10, L0 = 1: k(L − L0) = 20.
    v_b = (0.5, 0, 0), ω_b = (0, 0, 2) (body z = world z):
    V(P_b) = v_b + ω × (R r_b) = (0.5, 0, 0) + (−2, 0, 0) = (−1.5, 0, 0);  L̇ = −1.5.
    c = 4: T = 20 + 4(−1.5) = 14 (tension).  On a: +T u = (14, 0, 0); on b: (−14, 0, 0).
    Moments: a: (0, 1, 0) × (14, 0, 0) = (0, 0, −14);
             b: r_b × Rᵀ(−14, 0, 0) = (1, 0, 0) × (0, 14, 0) = (0, 0, 14)."""
    spec = {"dimension": 3, "bodies": [
        {"name": "a", "mass": 1.0, "inertia": [1, 1, 1]},
        {"name": "b", "mass": 2.0, "inertia": [1, 1, 1], "position": [3.0, 0, 0],
         "orientation": {"quaternion": Q_RZ90}, "velocity": [0.5, 0, 0],
         "angular_velocity": [0, 0, 2.0]}],
        "loads": [{"name": "k", "type": "spring", "bodies": ["a", "b"],
                   "at": [[0, 1.0, 0], [1.0, 0, 0]], "stiffness": 10.0, "rest_length": 1.0,
                   "damping": 4.0}]}
    asm = mbody.assemble(mbody.load(spec))
    close(rows(asm, asm.Q, "a"), [14, 0, 0, 0, 0, -14])
    close(rows(asm, asm.Q, "b"), [-14, 0, 0, 0, 0, 14])
    (fa,) = forces_named(asm, "a", "k")
    (fb,) = forces_named(asm, "b", "k")
    close(fa.W_vector, [14, 0, 0])
    close(fb.W_vector, [-14, 0, 0])
    close(fa.W_point, [0, 1, 0])
    close(fb.W_point, [3, 1, 0])
    close(fb.B_moment, [0, 0, 14])


def test_compressed_spring_pushes_apart():
    """L = 3 < L0 = 5, no motion: T = 10(3 − 5) = −20: a gets (−20, 0, 0), b (+20, 0, 0)."""
    spec = {"dimension": 3, "bodies": [
        {"name": "a", "mass": 1.0, "inertia": [1, 1, 1]},
        {"name": "b", "mass": 1.0, "inertia": [1, 1, 1], "position": [3.0, 0, 0]}],
        "loads": [{"type": "spring", "bodies": ["a", "b"], "at": [[0, 0, 0], [0, 0, 0]],
                   "stiffness": 10.0, "rest_length": 5.0}]}
    asm = mbody.assemble(mbody.load(spec))
    close(asm.Q, [-20, 0, 0, 0, 0, 0, 20, 0, 0, 0, 0, 0])


def test_planar_spring_to_ground_with_damping():
    """Ground point (0.5, 2); plate at the origin, θ = 0, end (0.5, 0) body axes.
    bodies [ground, plate]: d = P_plate − P_ground = (0, −2), L = 2, u = (0, −1).
    k = 100, L0 = 0.5: 150.  v = (0, −1), θ̇ = 0: L̇ = u · v = 1; c = 2: T = 152.
    On the plate (second end): −T u = (0, 152); M = r × F = 0.5 · 152 = 76."""
    spec = {"dimension": 2, "bodies": [
        {"name": "plate", "mass": 4.0, "inertia": 2.0, "velocity": [0, -1.0]}],
        "loads": [{"name": "k", "type": "spring", "bodies": ["ground", "plate"],
                   "at": [[0.5, 2.0], [0.5, 0]], "stiffness": 100.0, "rest_length": 0.5,
                   "damping": 2.0}]}
    asm = mbody.assemble(mbody.load(spec))
    close(asm.Q, [0, 152, 76])
    close(asm.solve().accelerations, [0, 38, 38])
    # spinning so the end moves with the plate's centre: V_end = v + θ̇ × r = (0, −1 + 0.5 θ̇)
    spec["bodies"][0]["angular_velocity"] = 2.0  # V_end = 0: no damping force
    close(mbody.assemble(mbody.load(spec)).Q, [0, 150, 75])


# -- gravity ------------------------------------------------------------------------------

def test_gravity_at_mass_centre_any_pose():
    spec = {"dimension": 3, "gravity": [0, 0, -9.81], "bodies": [
        {"name": "b", "mass": 3.0, "inertia": J_FULL, "position": [1.0, 2.0, 3.0],
         "orientation": {"quaternion": Q_RX90}}]}
    asm = mbody.assemble(mbody.load(spec))
    close(asm.Q, [0, 0, -29.43, 0, 0, 0])
    (g,) = [f for f in asm.bodies["b"].fbd.forces if f.kind == "gravity"]
    close(g.W_vector, [0, 0, -29.43])
    close(g.W_point, [1, 2, 3])
    close(g.B_moment, [0, 0, 0])
    planar = {"dimension": 2, "gravity": [0, -9.81], "bodies": [
        {"name": "p", "mass": 2.0, "inertia": 0.1, "angle": 1.0}]}
    close(mbody.assemble(mbody.load(planar)).solve().accelerations, [0, -9.81, 0])


# -- joint frames and G entries, per joint type --------------------------------------------

def _joint_frame_model(axis, typ="revolute", axis2=None):
    j = {"name": "J", "type": typ, "parent": "ground", "child": "c", "at": [0, 0, 0]}
    if axis is not None:
        j["axis"] = axis
    if axis2 is not None:
        j["axis2"] = axis2
    return mbody.load({"dimension": 3, "bodies": [{"name": "c", "mass": 1.0,
                                                   "inertia": [1, 1, 1]}], "joints": [j]})


@pytest.mark.parametrize(("axis", "frame"), [
    # z along the axis; x = least aligned world axis minus its z part; y = z × x.
    (None, np.eye(3)),
    ([0, 0, 1], np.eye(3)),
    # z = (0, 1, 1)/√2: |z| = (0, .71, .71) -> world x; x = (1, 0, 0);
    # y = z × x = (0, 1, −1)/√2
    ([0, 1, 1], np.column_stack(([1, 0, 0], [0, S2, -S2], [0, S2, S2]))),
    # z = (1, 1, 1)/√3: a three-way tie -> world x; x = (1,0,0) − z/√3 = (2, −1, −1)/3,
    # normalised (2, −1, −1)/√6; y = z × x = (0, 3, −3)/√18 = (0, 1, −1)/√2
    ([1, 1, 1], np.column_stack((np.array([2, -1, -1]) / np.sqrt(6), [0, S2, -S2],
                                 np.ones(3) / np.sqrt(3)))),
    # z = world x: least aligned = world y (first of y, z): x = (0, 1, 0), y = (0, 0, 1)
    ([1, 0, 0], np.column_stack(([0, 1, 0], [0, 0, 1], [1, 0, 0]))),
    # z = (0, 0, −1): x = world x, y = z × x = (0, −1, 0)
    ([0, 0, -1], np.column_stack(([1, 0, 0], [0, -1, 0], [0, 0, -1]))),
])
def test_spatial_joint_frame_rule(axis, frame):
    model = _joint_frame_model(axis, "spherical" if axis is None else "revolute")
    close(model.joints[0].W_E0, frame, 1e-15)
    asm = mbody.assemble(model)
    G = asm.G.toarray()
    for k, comp in enumerate(("Fx", "Fy", "Fz")):
        if f"J.{comp}" in asm.reactions:
            close(G[:3, asm.reactions.index(f"J.{comp}")], frame[:, k], 1e-15)


def _two_body_spatial(typ, axis=None, axis2=None):
    """Parent p at the origin turned Rz(90°); child c at (1, 2, 3) turned Rx(90°);
    joint at P = (1, 1, 1): r_p = (1, 1, 1), r_c = P − x_c = (0, −1, −2)."""
    j = {"name": "J", "type": typ, "parent": "p", "child": "c", "at": [1.0, 1.0, 1.0]}
    if axis is not None:
        j["axis"] = axis
    if axis2 is not None:
        j["axis2"] = axis2
    return mbody.load({"dimension": 3, "bodies": [
        {"name": "p", "mass": 1.0, "inertia": [1, 1, 1], "orientation": {"quaternion": Q_RZ90}},
        {"name": "c", "mass": 1.0, "inertia": [1, 1, 1], "position": [1.0, 2.0, 3.0],
         "orientation": {"quaternion": Q_RX90}}], "joints": [j]})


R_P, R_C = np.array([1.0, 1, 1]), np.array([0.0, -1, -2])
TILT = np.column_stack(([1, 0, 0], [0, S2, -S2], [0, S2, S2]))  # frame of axis (0, 1, 1)


def _expected_columns(comps, E, mt=None):
    """Hand rule: force e at P -> child [e, R_cᵀ(r_c × e)], parent −[e, R_pᵀ(r_p × e)];
    couple e -> child [0, R_cᵀ e], parent −[0, R_pᵀ e]."""
    out = []
    for comp in comps:
        e = mt if comp == "Mt" else E[:, "xyz".index(comp[1])]
        if comp[0] == "F":
            child = np.r_[e, RX90.T @ np.cross(R_C, e)]
            parent = -np.r_[e, RZ90.T @ np.cross(R_P, e)]
        else:
            child = np.r_[np.zeros(3), RX90.T @ e]
            parent = -np.r_[np.zeros(3), RZ90.T @ e]
        out.append(np.r_[parent, child])  # stacking order: p then c
    return np.column_stack(out)


@pytest.mark.parametrize(("typ", "axis", "axis2", "comps"), [
    ("revolute", [0, 1, 1], None, ("Fx", "Fy", "Fz", "Mx", "My")),
    ("prismatic", [0, 1, 1], None, ("Fx", "Fy", "Mx", "My", "Mz")),
    ("cylindrical", [0, 1, 1], None, ("Fx", "Fy", "Mx", "My")),
    ("universal", [0, 1, 1], [1, 0, 0], ("Fx", "Fy", "Fz", "Mt")),
    ("spherical", None, None, ("Fx", "Fy", "Fz")),
    ("fixed", None, None, ("Fx", "Fy", "Fz", "Mx", "My", "Mz")),
    ("fixed", [0, 1, 1], None, ("Fx", "Fy", "Fz", "Mx", "My", "Mz")),
])
def test_spatial_joint_columns(typ, axis, axis2, comps):
    model = _two_body_spatial(typ, axis, axis2)
    asm = mbody.assemble(model)
    assert asm.reactions == [f"J.{c}" for c in comps]
    E = np.eye(3) if axis is None else TILT
    # universal: Mt about axis × axis2 = (0, 1, 1)/√2 × (1, 0, 0) = (0, 1, −1)/√2
    mt = np.array([0, S2, -S2]) if typ == "universal" else None
    close(asm.G.toarray(), _expected_columns(comps, E, mt), 1e-14)


def test_spatial_revolute_fully_written_out():
    """World-axis revolute (axis z), component Fx, e = (1, 0, 0):
    child: r_c × e = (0, −1, −2) × (1, 0, 0) = (0, −2, 1); R_cᵀ (0, −2, 1) = (0, 1, 2);
    parent: r_p × e = (1, 1, 1) × (1, 0, 0) = (0, 1, −1); R_pᵀ (0, 1, −1) = (1, 0, −1).
    Universal Mt = (0, 1, −1)/√2: child R_cᵀ Mt = (0, −1, −1)/√2; parent R_pᵀ Mt =
    (1, 0, −1)/√2."""
    G = mbody.assemble(_two_body_spatial("revolute", [0, 0, 1])).G.toarray()
    close(G[:, 0], [-1, 0, 0, -1, 0, 1, 1, 0, 0, 0, 1, 2])
    U = mbody.assemble(_two_body_spatial("universal", [0, 1, 1], [1, 0, 0])).G.toarray()
    close(U[:, 3], [0, 0, 0, -S2, 0, S2, 0, 0, 0, 0, -S2, -S2], 1e-15)


def test_joint_frame_is_carried_by_the_parent():
    """Turn the parent by a further Rz(90°) (total 180°): its joint axes turn with it, so
    the revolute's Fx, world x at the file's pose, becomes Rz(90°)(1, 0, 0) = (0, 1, 0)."""
    model = _two_body_spatial("revolute", [0, 0, 1])
    s = model.initial
    q = s.quaternion.copy()
    q[0] = [0.0, 0.0, 0.0, 1.0]  # Rz(180°) = Rz(90°) · Rz(90°)
    G = mbody.assemble(model, s.replace(quaternion=q)).G.toarray()
    close(G[6:9, 0], [0, 1, 0], 1e-15)   # child Newton: Rz(90°)(1, 0, 0)
    close(G[0:3, 0], [0, -1, 0], 1e-15)  # parent: the opposite


# planar: parent p at the origin, θ = 90°; child c at (2, 0), θ = 0; joint at (1, 0.5).
# r_p = (1, 0.5), r_c = (−1, 0.5).  2-D cross r × e = r_x e_y − r_y e_x.

def _two_body_planar(typ, axis=None):
    j = {"name": "J", "type": typ, "parent": "p", "child": "c", "at": [1.0, 0.5]}
    if axis is not None:
        j["axis"] = axis
    return mbody.load({"dimension": 2, "bodies": [
        {"name": "p", "mass": 1.0, "inertia": 1.0, "angle": "90 deg"},
        {"name": "c", "mass": 1.0, "inertia": 1.0, "position": [2.0, 0.0]}], "joints": [j]})


@pytest.mark.parametrize(("typ", "axis", "expected"), [
    # Fx, e = (1, 0): child r_c × e = −0.5; parent −(r_p × e) = −(−0.5) = 0.5.
    # Fy, e = (0, 1): child r_c × e = −1; parent −(r_p × e) = −1.
    ("revolute", None, {"J.Fx": [-1, 0, 0.5, 1, 0, -0.5], "J.Fy": [0, -1, -1, 0, 1, -1]}),
    # axis (1, 1): x = (1, 1)/√2, y = (−1, 1)/√2 = s(−1, 1).
    # Fy: child r_c × y = s(−1·1 − 0.5·(−1)) = −0.5 s; parent −[−s, s, s(1·1 − 0.5·(−1))]
    # = [s, −s, −1.5 s].  Mz: child 1, parent −1.
    ("prismatic", [1.0, 1.0], {"J.Fy": [S2, -S2, -1.5 * S2, -S2, S2, -0.5 * S2],
                               "J.Mz": [0, 0, -1, 0, 0, 1]}),
    ("fixed", None, {"J.Fx": [-1, 0, 0.5, 1, 0, -0.5], "J.Fy": [0, -1, -1, 0, 1, -1],
                     "J.Mz": [0, 0, -1, 0, 0, 1]}),
])
def test_planar_joint_columns(typ, axis, expected):
    model = _two_body_planar(typ, axis)
    asm = mbody.assemble(model)
    assert asm.reactions == list(expected)
    close(asm.G.toarray(), np.column_stack(list(expected.values())), 1e-15)
    if axis is not None:
        close(model.joints[0].W_E0[:2, :2], [[S2, -S2], [S2, S2]], 1e-15)


# -- the action/reaction sign ---------------------------------------------------------------

def test_reaction_sign_on_child_and_parent():
    """Known A.Fx = 5, A.Fy = −2 at a pin through both mass centres' line:
    child (m = 2) gets +R: a = (2.5, −1); parent (m = 4) gets −R: a = (−1.25, 0.5).
    Pin at (1, 0): child at (2, 0) -> r_c = (−1, 0): M_c = r_c × R = (−1)(−2) − 0 = 2;
    parent at origin -> r_p = (1, 0): M_p = r_p × (−R) = (1)(2) − 0 = 2."""
    spec = {"dimension": 2, "bodies": [
        {"name": "p", "mass": 4.0, "inertia": 1.0},
        {"name": "c", "mass": 2.0, "inertia": 0.5, "position": [2.0, 0]}],
        "joints": [{"name": "A", "type": "revolute", "parent": "p", "child": "c",
                    "at": [1.0, 0]}],
        "reactions": {"A.Fx": 5.0, "A.Fy": -2.0}}
    asm = mbody.assemble(mbody.load(spec))
    close(asm.solve().accelerations, [-1.25, 0.5, 2.0, 2.5, -1.0, 4.0])
    (cx,) = forces_named(asm, "c", "A.Fx")
    (px,) = forces_named(asm, "p", "A.Fx")
    close(cx.W_vector, [5, 0, 0])
    close(px.W_vector, [-5, 0, 0])
    close(cx.W_point, [1, 0, 0])
    close(px.W_point, [1, 0, 0])
    assert cx.kind == px.kind == "reaction" and cx.value == 5.0
    eq = asm.bodies["c"].newton[0]
    assert eq.reactions == {"A.Fx": 1.0}
    assert asm.bodies["p"].newton[0].reactions == {"A.Fx": -1.0}
    # the API's known= overrides and adds to the file's values
    close(asm.solve(known={"A.Fx": 0.0}).accelerations, [0, 0.5, 2.0, 0, -1.0, 4.0])


def test_reaction_sign_ground_parent_spatial():
    """Ground parent: only the child carries +R; a moment component acts as a couple."""
    spec = {"dimension": 3, "bodies": [{"name": "c", "mass": 2.0, "inertia": [1, 2, 2.5],
                                        "position": [0, 0, -1.0]}],
            "joints": [{"name": "A", "type": "fixed", "parent": "ground", "child": "c",
                        "at": [0, 0, 0]}],
            "reactions": {"A.Fx": 4.0, "A.Fy": 0, "A.Fz": 0, "A.Mx": 0, "A.My": 0,
                          "A.Mz": 8.0}}
    # child arm r_c = (0, 0, 1): r × (4, 0, 0) = (0, 4, 0); plus couple (0, 0, 8):
    # ω̇ = (0, 4/2, 8/2.5) = (0, 2, 3.2).
    acc = mbody.assemble(mbody.load(spec)).solve().accelerations
    close(acc, [2.0, 0, 0, 0, 2.0, 3.2])


# -- orientation conventions and inertia from a shape ---------------------------------------

@pytest.mark.parametrize(("orientation", "body_x", "body_y"), [
    # intrinsic ZYX [a, b, c] = Rz(a) Ry(b) Rx(c)
    ({"euler": ["90 deg", 0, 0], "sequence": "ZYX"}, [0, 1, 0], [-1, 0, 0]),
    # Ry(90°): x -> (0, 0, −1), y -> y
    ({"euler": [0, "90 deg", 0], "sequence": "ZYX"}, [0, 0, -1], [0, 1, 0]),
    # Rz(90°) Ry(90°): x -> Rz(0, 0, −1) = (0, 0, −1); y -> Rz(0, 1, 0) = (−1, 0, 0)
    ({"euler": ["90 deg", "90 deg", 0]}, [0, 0, -1], [-1, 0, 0]),
    # extrinsic xyz [c, b, a] is the same rotation as intrinsic ZYX [a, b, c]
    ({"euler": [0, "90 deg", "90 deg"], "sequence": "xyz"}, [0, 0, -1], [-1, 0, 0]),
    ({"quaternion": [S2, 0, 0, S2]}, [0, 1, 0], [-1, 0, 0]),
    ({"quaternion": [2.0, 0, 0, 2.0]}, [0, 1, 0], [-1, 0, 0]),  # normalised (with a warning)
    ({"matrix": RZ90.tolist()}, [0, 1, 0], [-1, 0, 0]),
])
def test_orientation_conventions_turn_body_frame_loads(orientation, body_x, body_y):
    """A body-frame force along body x (then y) shows up along R e_x (R e_y) in world."""
    spec = {"dimension": 3, "bodies": [{"name": "b", "mass": 1.0, "inertia": [1, 1, 1],
                                        "orientation": orientation}],
            "loads": [{"type": "force", "body": "b", "force": [1.0, 0, 0], "frame": "body"},
                      {"type": "force", "body": "b", "force": [0, 2.0, 0], "frame": "body"}]}
    close(mbody.assemble(mbody.load(spec)).Q[:3], np.add(body_x, 2 * np.asarray(body_y)))


@pytest.mark.parametrize(("dimension", "shape", "mass", "expected"), [
    # box [a, b, c]: m/12 (b² + c², a² + c², a² + b²) = (0.05, 0.17, 0.2) for m = 12
    (3, {"box": [0.4, 0.2, 0.1]}, 12.0, [0.05, 0.17, 0.2]),
    # cylinder (axis z): m(3r² + L²)/12 = 2(0.03 + 0.36)/12 = 0.065; m r²/2 = 0.01
    (3, {"cylinder": {"radius": 0.1, "length": 0.6}}, 2.0, [0.065, 0.065, 0.01]),
    # sphere: 2/5 m r² = 0.4 · 5 · 0.25 = 0.5
    (3, {"sphere": {"radius": 0.5}}, 5.0, [0.5, 0.5, 0.5]),
    # planar box [w, h]: m(w² + h²)/12 = 10 · 1.64 / 12
    (2, {"box": [1.0, 0.8]}, 10.0, [10 * 1.64 / 12]),
    # planar disc: m r²/2 = 12.5 · 0.04 / 2 = 0.25
    (2, {"disc": {"radius": 0.2}}, 12.5, [0.25]),
])
def test_inertia_from_shape(dimension, shape, mass, expected):
    spec = {"dimension": dimension, "bodies": [{"name": "b", "mass": mass, "shape": shape}]}
    M = mbody.assemble(mbody.load(spec)).M.toarray()
    k = 3 if dimension == 3 else 1
    close(np.diag(M)[-k:], expected, 1e-14)
