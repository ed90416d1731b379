"""Readable text for models, assemblies and solutions (what the CLI prints)."""

from __future__ import annotations

import numpy as np

from mbody import conventions as cv
from mbody.equations.assemble import Assembly, Solution
from mbody.equations.coordinates import size
from mbody.equations.fbd_text import body_text, force_cells
from mbody.equations.topology import Topology
from mbody.model.model import Model, State
from mbody.model.reprs import count
from mbody.util.formatting import LENGTH_RTOL, NOISE, quiet
from mbody.util.formatting import clean as _clean
from mbody.util.formatting import num as _n
from mbody.util.formatting import table as _table
from mbody.util.formatting import vec as _v

__all__ = ["assembly_text", "body_text", "force_cells", "graph_summary", "model_summary",
           "pose_text", "reaction_table_text", "solution_text", "world_reaction_text"]


def _speed_law(offset: float, rate: float) -> str:
    """A ``speed`` driver's law as `check` prints it, 6 significant digits like the rest:
    ``0.523599 - 62.8319*t`` (the law itself keeps every digit: `DriverTable.laws`)."""
    term = f"{_n(abs(rate))}*t"
    if offset == 0:
        return term if rate >= 0 else f"-{term}"
    return f"{_n(offset)} {'-' if rate < 0 else '+'} {term}"


def model_summary(model: Model, topo: Topology) -> str:
    dim = model.dimension
    kind = "planar" if dim == cv.PLANAR else "spatial"
    out = [f"model {model.name!r}: {kind}, {count(model.n, 'body', 'bodies')}, "
           f"{count(len(model.loads), 'load')}, {count(len(model.joints), 'joint')}"
           + (f"  [{model.file}]" if model.file else "")]
    if model.description:
        out.append(f"  {model.description.strip()}")
    if np.any(model.gravity):
        out.append(f"gravity {_v(model.gravity, dim)} m/s^2 (world)")
    out.append("")
    out.append(f"bodies ({model.n}, in stacking order):")
    shown = model.body_names[:50]
    for name in shown:
        b = model.bodies[name]
        if b.particle:
            inertia = "particle (no rotational inertia)"
        elif dim == cv.PLANAR:
            inertia = f"I_G {_n(b.I_G)} kg m^2"
        else:
            J = b.inertia
            inertia = ("I " + _v(np.diag(J), 3) if np.allclose(J, np.diag(np.diag(J)))
                       else "I full tensor, principal " + _v(np.linalg.eigvalsh(J), 3))
            inertia += " kg m^2"
        out.append(f"  {name:<14} m {_n(b.mass)} kg, {inertia}")
    if model.n > len(shown):
        out.append(f"  ... and {model.n - len(shown)} more")
    if model.loads:
        out.append(f"loads ({len(model.loads)}):")
        for ld in model.loads[:50]:
            vec = ld.vector  # a force's or torque's (a spring has none)
            if ld.type == "spring":
                what = (f"spring {ld.bodies[0]} - {ld.bodies[1]}, k {_n(ld.stiffness)} N/m, "
                        f"rest {_n(ld.rest_length)} m, damping {_n(ld.damping)} N s/m")
            elif vec is None:  # not given by the loader; named rather than failing
                what = f"{ld.type} on {ld.bodies[0]}"
            elif ld.type == "torque":
                what = (f"torque on {ld.bodies[0]}: "
                        + (f"{_n(vec[2])} N m" if dim == cv.PLANAR
                           else f"{_v(vec, 3)} N m ({ld.frame} axes)"))
            else:
                what = (f"force on {ld.bodies[0]}: {_v(vec, dim)} N ({ld.frame} axes) "
                        f"at {_v(ld.at[0], dim)} m")
            if ld.expressions:  # time-varying components: show the formulas, not t = 0
                what += "; varying: " + ", ".join(
                    f"{'xyz'[k]} = {e}" for k, e in sorted(ld.expressions.items()))
            out.append(f"  {ld.name:<14} {what}")
    if model.joints:
        out.append(f"joints ({len(model.joints)}):")
        jt = model.joint_table
        for k, j in enumerate(model.joints[:50]):
            if jt.body_points[k]:  # the file gives the point on each body
                where = (f"{_v(jt.B_r_parent[k], dim)} on {j.parent}, "
                         f"{_v(jt.B_r_child[k], dim)} on {j.child}")
            else:
                where = _v(j.at, dim)
            out.append(f"  {j.name:<14} {j.type} {j.parent} -> {j.child} at {where}: "
                       + ", ".join(j.labels))
    drivers = model.drivers
    if drivers is not None and len(drivers):
        out.append(f"drivers ({len(drivers)}):")
        for k, (name, j, (law, _, _), label) in enumerate(zip(
                drivers.names, drivers.joint.tolist(), drivers.laws, drivers.labels,
                strict=True)):
            unit = "rad" if label.endswith(".M") else "m"
            rate = drivers.speed[k] if k < len(drivers.speed) else None
            out.append(f"  {name:<14} {model.joints[j].name}: "
                       f"{law.text if rate is None else _speed_law(drivers.offset[k], rate)} "
                       f"({unit}, t in s); effort {label}")
    unknown = [r for r in model.reactions if r not in model.known_reactions]
    out.append(f"reaction unknowns ({len(unknown)}): " + (", ".join(unknown[:40]) or "none")
               + (" ..." if len(unknown) > 40 else ""))
    if model.known_reactions:
        out.append("known reactions: " + ", ".join(
            f"{k} = {model.known_expressions.get(k) or _n(v)}"
            for k, v in model.known_reactions.items()))
    if model.file_state is not None:  # assembled at load (joint points per body, drivers)
        moved = assembly_moves(model)
        out.append("assembled pose (every joint and driver holds at t = 0): "
                   + "; ".join(moved) if moved else "assembled pose: the file's pose already "
                   "satisfies every joint and driver at t = 0")
        changed = assembly_velocity_changes(model)
        if changed:  # the drivers' rates, or velocities the joints did not allow
            out.append("assembled velocities (every joint's and driver's rate holds at "
                       "t = 0; the change of least kinetic energy): " + "; ".join(changed))
    out.append("")
    out.append(graph_summary(model, topo))
    for w in model.warnings:
        out.append(f"warning: {w}")
    return "\n".join(out)


def assembly_moves(model: Model) -> list[str]:
    """How far each body moved from the file's pose to the assembled one, in words."""
    before = model.file_state
    if before is None:
        return []
    d = np.linalg.norm(model.initial.position - before.position, axis=1)
    dot = np.abs(np.einsum("ij,ij->i", before.quaternion, model.initial.quaternion))
    turned = np.degrees(2.0 * np.arccos(dot.clip(0.0, 1.0)))
    return [f"{name} moved {dk * 1e3:.3g} mm, turned {ak:.3g} deg"
            for name, dk, ak in zip(model.body_names, d.tolist(), turned.tolist(), strict=True)
            if dk > 1e-12 or ak > 1e-10]


def assembly_velocity_changes(model: Model) -> list[str]:
    """Each body whose velocity or angular velocity the assembly changed, with the new and
    the file's values, in words (planar: the spin about z, signed; spatial: magnitudes)."""
    before = model.file_state
    if before is None:
        return []
    now = model.initial
    planar = model.dimension == cv.PLANAR

    def speeds(s: State, i: int) -> str:
        w = s.omega[i][2] if planar else np.linalg.norm(s.omega[i])
        return f"{_n(float(np.linalg.norm(s.velocity[i])))} m/s, {_n(float(w))} rad/s"

    out = []
    for i, name in enumerate(model.body_names):
        dv = float(np.linalg.norm(now.velocity[i] - before.velocity[i]))
        dw = float(np.linalg.norm(now.omega[i] - before.omega[i]))
        if dv > 1e-12 or dw > 1e-12:
            out.append(f"{name} {speeds(now, i)} (the file's {speeds(before, i)})")
    return out


def pose_text(model: Model, state: State, angle_tol: float = NOISE) -> str:
    """Each body's mass centre (world, m) and orientation at `state`: the angle about z
    (deg) in a planar model, the quaternion (w, x, y, z) in a spatial one. What the pose
    was solved to prints as 0 below the solver's tolerance: a coordinate below
    `LENGTH_RTOL` of the model's size, an angle (rad; a quaternion's component, half one)
    below `angle_tol` (an equilibrium's: `mbody.solve.linearize.STEADY_RTOL`)."""
    rows = []
    planar = model.dimension == cv.PLANAR
    length_tol = max(NOISE, LENGTH_RTOL * size(model))
    for i, name in enumerate(model.body_names):
        q = state.quaternion[i]
        angle = quiet(float(2.0 * np.arctan2(q[3], q[0])), angle_tol)
        turn = (f"{_n(np.degrees(angle))} deg" if planar
                else "(" + ", ".join(_n(c, angle_tol) for c in q) + ")")
        rows.append([name, _v(state.position[i], model.dimension, length_tol), turn])
    lines = ["pose (mass centres in world axes, m):"]
    lines += _table(["body", "position", "angle" if planar else "quaternion (w, x, y, z)"],
                    rows)
    return "\n".join(lines)


def graph_summary(model: Model, topo: Topology) -> str:
    per = 3 if model.dimension == cv.PLANAR else 6
    # the counts of model.graph's nodes and edges, without building it (networkx is slow
    # to import)
    lines = [f"graph: {model.n + 1} nodes (bodies + ground), "
             f"{count(len(model.joints), 'joint edge')}; "
             + ("a tree (no closed loops)" if topo.is_tree
                else f"{count(topo.loops, 'closed loop')}")]
    lines.append(f"  connected parts: {len(topo.parts)}")
    for p in topo.parts[:10]:
        text = ", ".join(p[:12]) + (" ..." if len(p) > 12 else "")
        lines.append("    " + (text + " (nothing attached)" if p == [cv.GROUND] else text))
    if topo.floating:
        lines.append(f"  attached to nothing ({len(topo.floating)}): "
                     + ", ".join(topo.floating[:12]) + (" ..." if len(topo.floating) > 12 else ""))
    coords = f"{per} x {model.n} bodies"
    if model.has_particles:
        k = int(model.particle.sum())
        coords = (f"{per} x {model.n - k} bodies + {model.dimension} x {k} particle"
                  + ("s" if k > 1 else "") if k < model.n
                  else f"{model.dimension} x {k} particle" + ("s" if k > 1 else ""))
    if topo.rank is None:
        lines.append(f"mobility: {topo.mobility} = {coords} - "
                     f"{topo.constraints} reaction components (Gruebler; rank not computed)")
    else:
        lines.append(f"mobility: {topo.mobility} = {coords} - {topo.rank} "
                     f"independent constraints ({topo.constraints} reaction components)")
    if topo.redundant:
        lines.append(redundancy_warning(len(topo.redundant), topo.indeterminate))
    return "\n".join(lines)


def redundancy_warning(count: int, groups: list[tuple[str, ...]]) -> str:
    """What `check` says of redundant constraints: how many, and the components of each
    indeterminacy (all of them, not one arbitrary member: their values are not unique)."""
    head = f"warning: {count} redundant constraint{'s' if count != 1 else ''}: "
    if len(groups) == 1:
        return (head + f"the reactions {', '.join(groups[0])} (all {len(groups[0])}) share "
                "one indeterminacy (a self-stress, which loads no body): their values are "
                "not unique")
    listed = "; ".join("{" + ", ".join(g) + "}" for g in groups)
    return (head + f"{len(groups)} indeterminacies (self-stresses, which load no body), "
            f"each shared by the reactions in braces: {listed}; their values are not unique")


def assembly_text(asm: Assembly, max_bodies: int = 200) -> str:
    model = asm.model
    parts = [f"model {model.name!r}: M v_dot + b = Q + G lambda; rows per body: "
             + ", ".join(cv.PLANAR_ROWS if model.dimension == 2 else cv.SPATIAL_ROWS)
             + ("" if model.dimension == 2 else
                " (Newton in world axes, Euler in body axes)")
             + ("; a particle has translation rows only" if model.has_particles else "")]
    for name in model.body_names[:max_bodies]:
        parts.append(body_text(asm.bodies[name], model.dimension))
    if model.n > max_bodies:
        parts.append(f"... {model.n - max_bodies} more bodies (use --body NAME)")
    sh = asm.shape
    parts.append("stacked: " + ", ".join(f"{k} {'x'.join(map(str, v))}" for k, v in sh.items())
                 + f"  (reaction unknowns: {len(asm.reactions)})")
    return "\n\n".join(parts)


def solution_text(sol: Solution, model: Model) -> str:
    rows = cv.PLANAR_ROWS if model.dimension == 2 else cv.SPATIAL_ROWS
    units = {"x": "m/s^2", "y": "m/s^2", "z": "m/s^2", "theta": "rad/s^2"}
    lines = [f"accelerations of {model.name!r} (Newton rows world axes"
             + (", Euler rows body axes):" if model.dimension == 3 else "):")]
    acc = _clean(sol.accelerations)
    width = max(14, *(len(b) + 2 for b in model.body_names))  # a long name keeps its column
    for i, name in enumerate(model.body_names):
        idx = model.body_rows(i)
        lines.append(f"  {name:<{width}}" + "  ".join(
            f"{cv.ACCELERATION_NAMES[r]} = {_n(v)} {units.get(r, 'rad/s^2')}"
            for r, v in zip(rows[:len(idx)], acc[idx], strict=True)))
    return "\n".join(lines)


def joint_status(model: Model, sol: Solution) -> dict[str, str]:
    """joint or driver name -> what the solve did with its joint-frame components: "solved",
    "given", "not unique" (redundant constraints), or "partly solved" when they differ:
    the status of a joint's world-axes force and moment, which mix its components."""
    solved, not_unique = set(sol.solved), set(sol.not_unique)
    status: dict[str, str] = {}
    for label in model.reactions:
        name = label.split(".", 1)[0]
        s = ("not unique" if label in not_unique else
             "solved" if label in solved else "given")
        if status.get(name, s) != s:
            s = "partly solved"
        status[name] = s
    return status


def world_reaction_text(model: Model, sol: Solution) -> str:
    """A solution's reactions in world axes (``Assembly.solve(axes="world")``): each joint's
    force and moment on its child at its joint point along world x, y, z, then the drivers'
    efforts; a joint's status is that of its joint-frame components."""
    if not sol.reactions:
        return ""
    drivers = set(model.reaction_table.driver_names)
    status = joint_status(model, sol)
    child = {j.name: j.child for j in model.joints}
    lam = _clean(np.array(list(sol.reactions.values()), dtype=float))
    rows = []
    for label, v in zip(sol.reactions, lam, strict=True):
        name, comp = label.split(".", 1)
        unit = "N m" if comp.startswith("M") else "N"
        what = "driver effort" if name in drivers else f"on {child[name]}"
        rows.append([name, comp, what, f"{_n(v)} {unit}", status.get(name, "given")])
    lines = ["joint reactions in world axes: each joint's force F and moment M on its child "
             "at the joint point (-F, -M on the parent); drivers' efforts about or along "
             "their joint's axis"]
    lines += _table(["joint", "comp", "acts", "value", "status"], rows)
    if sol.residual is not None:
        lines.append(f"solve: {sol.method}; relative backward error {sol.residual:.1e}")
    for w in sol.warnings:
        lines.append(f"warning: {w}")
    return "\n".join(lines)


def reaction_table_text(asm: Assembly, sol: Solution) -> str:
    """Joint, component, its axis (world components at this state), value, status; then
    each joint's net force and couple on its child (at the joint point) and on its parent
    (equal and opposite; a particle link's force at its two ends)."""
    model = asm.model
    dim = model.dimension
    if not sol.reactions:
        return ""
    cols = asm.columns
    rt = model.reaction_table
    lam = _clean(np.array([sol.reactions[r] for r in model.reactions]))
    solved, not_unique = set(sol.solved), set(sol.not_unique)
    rows = []
    for c, label in enumerate(model.reactions):
        joint, comp = label.split(".", 1)
        unit = "N m" if cols.is_moment[c] else "N"
        status = ("not unique" if label in not_unique else
                  "solved" if label in solved else "given")
        # a planar couple turns about z: its axis has no in-plane part to print
        axis = "about z" if dim == cv.PLANAR and cols.is_moment[c] else _v(cols.W_e[c], dim)
        rows.append([joint, comp, axis, f"{_n(lam[c])} {unit}", status])
    lines = ["joint reactions: each component acts along (or about) its joint-frame axis, "
             "+R on the child and -R on the parent"]
    lines += _table(["joint", "comp", "axis (world)", "value", "status"], rows)
    lines.append("net load of each joint at its joint point (world axes):")
    # each joint's components summed in their order, all joints at once (a mask per
    # joint was quadratic in the joints: 2.4 s at 8000)
    F_all = np.zeros((len(model.joints), 3))
    C_all = np.zeros((len(model.joints), 3))
    moment = np.asarray(cols.is_moment, dtype=bool)
    np.add.at(F_all, rt.joint[~moment], lam[~moment, None] * cols.W_e[~moment])
    np.add.at(C_all, rt.joint[moment], lam[moment, None] * cols.W_e[moment])
    F_all, C_all = _clean(F_all), _clean(C_all)
    firsts = np.full(len(model.joints), -1)
    firsts[rt.joint[::-1]] = np.arange(len(rt.joint))[::-1]  # each joint's first component
    for jn, j in enumerate(model.joints):
        first = int(firsts[jn])
        P = cols.W_P[first]
        F, C = F_all[jn], C_all[jn]
        Cs = _n(C[2]) if dim == cv.PLANAR else _v(C, 3)
        mCs = _n(-C[2]) if dim == cv.PLANAR else _v(-C, 3)
        if rt.link[first]:  # a rigid link to a particle: its two ends are apart
            Pp = P + rt.length[first] * cols.W_e[first]
            lines.append(f"  {j.name} (link, {_n(rt.length[first])} m): on child {j.child} "
                         f"at {_v(P, dim)}: F {_v(F, dim)} N; on parent {j.parent} at "
                         f"{_v(Pp, dim)}: F {_v(-F, dim)} N")
            continue
        lines.append(f"  {j.name} at {_v(P, dim)}: on child {j.child}: F {_v(F, dim)} N, "
                     f"C {Cs} N m; on parent {j.parent}: F {_v(-F, dim)} N, C {mCs} N m")
    if sol.residual is not None:
        cond = ""
        if sol.condition is not None:
            cond = ("; singular (redundant constraints)" if not np.isfinite(sol.condition)
                    else f"; condition estimate {sol.condition:.2e}")
        lines.append(f"solve: {sol.method}; relative backward error {sol.residual:.1e}{cond}")
    for w in sol.warnings:
        lines.append(f"warning: {w}")
    return "\n".join(lines)
