"""The names a student's equation may use for one body, and what each stands for.

Unknowns (the equation is linear in them):

- ``a_x, a_y`` (spatial also ``a_z``): the mass centre's acceleration, world axes;
- ``alpha`` (planar) or ``alpha_1, alpha_2, alpha_3`` (spatial, body axes): the angular
  acceleration;
- every unknown reaction component by its label (``O.Fy``).

Numbers taken from the model at its state:

- ``m``; planar ``I_G``; spatial ``I_1, I_2, I_3`` (principal moments, when the tensor is
  diagonal in body axes) and every tensor entry ``I_11, I_12, ... I_33``;
- ``w`` and ``theta`` (planar) or ``w_1, w_2, w_3`` (spatial, body axes);
- ``g``, the magnitude of gravity; ``pi``; ``t``, the time of the state;
- a reaction whose value the model gives (``reactions:`` in the file), by its label;
- each applied load's components by name, as `mbody assemble --symbolic` writes them
  (``F_push_x`` world axes, ``F_push_1`` body axes, ``M_motor_3``, ``T_spring``).

Aliases (``omega``, ``ω``, ``α``, ``ax``, ``theta_ddot``...) map onto these names.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from mbody import conventions as cv
from mbody.equations.symbolic import load_symbols
from mbody.errors import did_you_mean, name_list
from mbody.model.model import Model, State

PLANAR_ACCELERATIONS = ("a_x", "a_y", "alpha")
SPATIAL_ACCELERATIONS = ("a_x", "a_y", "a_z", "alpha_1", "alpha_2", "alpha_3")

_ALIASES_BOTH = {
    "ax": "a_x", "ay": "a_y", "a_Gx": "a_x", "a_Gy": "a_y", "a_gx": "a_x", "a_gy": "a_y",
    "x_ddot": "a_x", "y_ddot": "a_y", "mass": "m",
}
_ALIASES_PLANAR = {
    "alpha_z": "alpha", "theta_ddot": "alpha", "thetaddot": "alpha", "α": "alpha",
    "omega": "w", "omega_z": "w", "w_z": "w", "theta_dot": "w", "thetadot": "w", "ω": "w",
    "omega_dot": "alpha", "w_dot": "alpha", "wdot": "alpha", "omegadot": "alpha",
    "θ": "theta", "I": "I_G", "I_zz": "I_G", "I_z": "I_G",
}
_ALIASES_SPATIAL = {
    "az": "a_z", "a_Gz": "a_z", "a_gz": "a_z", "z_ddot": "a_z",
    **{f"{a}{k}": f"alpha_{k}" for k in (1, 2, 3)
       for a in ("alpha", "α_", "α", "wdot_", "w_dot_", "omega_dot_", "omegadot_", "ω_dot_")},
    **{f"{a}{k}{d}": f"alpha_{k}" for k in (1, 2, 3) for a in ("w", "w_", "omega", "omega_")
       for d in ("dot", "_dot")},
    **{f"{a}{k}": f"w_{k}" for k in (1, 2, 3) for a in ("w", "omega_", "omega", "ω_", "ω")},
    **{f"I{k}": f"I_{k}" for k in (1, 2, 3)},
    **{f"I{j}{k}": f"I_{j}{k}" for j in (1, 2, 3) for k in (1, 2, 3)},
}

SUMMARY_NAMES = 40
"""Most names an unknown name's message lists (`Vocabulary.summary`), then how many more."""

_SUBSCRIPT = re.compile("_?[\u2080-\u2089]+")
_DIGITS = str.maketrans("\u2080\u2081\u2082\u2083\u2084\u2085\u2086\u2087\u2088\u2089",
                        "0123456789")
"""Subscript digits pasted from a textbook (I₁, ω₂) read as I_1, ω_2."""
_LETTER_AXIS = re.compile(r"(w|omega|ω|alpha|α|w_?dot|omega_?dot|ω_?dot|I)_?([xyz]|[xyz]{2})"
                          r"(_?dot)?")
"""Angular names with a letter axis: on a spatial body its axes are numbered."""

MEANINGS = {
    "a_x": "mass-centre acceleration along world x (m/s^2)",
    "a_y": "mass-centre acceleration along world y (m/s^2)",
    "a_z": "mass-centre acceleration along world z (m/s^2)",
    "alpha": "angular acceleration, planar (rad/s^2)",
    "alpha_1": "angular acceleration about body axis 1 (rad/s^2)",
    "alpha_2": "angular acceleration about body axis 2 (rad/s^2)",
    "alpha_3": "angular acceleration about body axis 3 (rad/s^2)",
    "m": "mass (kg)", "I_G": "moment of inertia about the mass centre (kg m^2)",
    "w": "angular velocity, planar (rad/s)", "theta": "angle, planar (rad)",
    "g": "magnitude of gravity (m/s^2)", "pi": "3.14159...",
    "t": "the time of the state the equations are written at (s)",
}
"""What each fixed name of the vocabulary stands for (docs and error hints)."""


@dataclass(frozen=True)
class Vocabulary:
    """The names an equation of one body may use.

    Parameters
    ----------
    body : str
        The body's name.
    dimension : int
        2 (planar) or 3 (spatial).
    accelerations : tuple of str
        The body's acceleration unknowns in row order (a particle's: translations only).
    reactions : tuple of str
        Every unknown reaction label of the model (a label of another body's joint is
        understood, and then reported as not acting on this body).
    values : dict of str to float
        Every name that stands for a number of the model at its state.
    aliases : dict of str to str
        Other spellings -> the names above.
    absent : dict of str to str
        Names that exist for other bodies or models but not here -> why (for the error).
    acting : tuple of str, optional
        The unknown reaction labels of the joints that touch this body (the ones on its
        free body): the only ones an error's list of names and suggestions offer.
        Defaults to `reactions`.
    hinted : bool
        Whether an unknown name's error carries a did-you-mean (`resolve`); `quiet` is the
        same vocabulary without: what an answers file's problems past those its error
        shows use (each did-you-mean is a pass over the names: thousands for a large
        model's Lagrange equations).
    """

    body: str
    dimension: int
    accelerations: tuple[str, ...]
    reactions: tuple[str, ...]
    values: dict[str, float]
    aliases: dict[str, str] = field(default_factory=dict)
    absent: dict[str, str] = field(default_factory=dict)
    acting: tuple[str, ...] | None = None
    hinted: bool = True

    @cached_property
    def quiet(self) -> Vocabulary:
        """This vocabulary, its errors without a did-you-mean (`hinted`)."""
        return self if not self.hinted else dataclasses.replace(self, hinted=False)

    @property
    def own_reactions(self) -> tuple[str, ...]:
        """The unknown reactions that act on this body (`acting`, else every one)."""
        return self.reactions if self.acting is None else self.acting

    @property
    def unknowns(self) -> tuple[str, ...]:
        """The accelerations, then the unknown reaction labels."""
        return self.accelerations + self.reactions

    @property
    def names(self) -> list[str]:
        """Every name accepted (canonical names first, then aliases)."""
        return [*self.unknowns, *self.values, *self.aliases]

    def resolve(self, name: str) -> str:
        """The canonical name of `name`.

        Parameters
        ----------
        name : str
            A name as written in an equation.

        Returns
        -------
        str
            An unknown's name or a key of `values`.

        Raises
        ------
        KeyError
            The name is not in the vocabulary; the message says why, with a
            did-you-mean over the vocabulary (when `hinted`).
        """
        name = self._spelt(name)
        if name in self.values or name in self._unknown_set:
            return name
        if name in self.absent:
            raise KeyError(self.absent[name])
        hint = self._hint(name) if self.hinted else ""
        joint = name.partition(".")[0] + "."
        if "." in name and not hint and any(r.startswith(joint) for r in self.reactions) \
                and not any(r.startswith(joint) for r in self.own_reactions):
            hint = (f"joint {joint[:-1]} does not act on {self.body}: its reactions are not "
                    "on this free body")
        what = (f"no reaction component {name!r} in this model" if "." in name else
                f"unknown name {name!r} for body {self.body!r}")
        raise KeyError(what + (f"; {hint}" if hint else "")
                       + f" (the names: {self.summary()})")

    def canonical(self, name: str) -> str | None:
        """`resolve`'s answer, or None for a name outside the vocabulary (no message, no
        did-you-mean: a membership test)."""
        name = self._spelt(name)
        return name if name in self.values or name in self._unknown_set else None

    def _spelt(self, name: str) -> str:
        """`name` with subscript digits as _1 and an alias as its canonical name."""
        name = _SUBSCRIPT.sub(lambda mo: "_" + mo.group(0).lstrip("_").translate(_DIGITS),
                              name)
        return self.aliases.get(name, name)

    def _hint(self, name: str) -> str:
        """A way to fix an unknown `name`: a product written without '*', a body axis
        written as a letter, or the closest name (canonical names first: a suggestion of
        'az' or 'ω_1' for 'a' or 'M_1' helps no one)."""
        if self.dimension == cv.SPATIAL and _LETTER_AXIS.fullmatch(name):
            return ("a spatial body's angular velocity, angular acceleration and inertia are "
                    "along its body axes, numbered: w_1, w_2, w_3; alpha_1 ...; I_1 ... "
                    "(tensor entries I_11, I_12 ...); letters x, y, z are world axes (a_x)")
        for k in range(1, len(name)):
            a, b = name[:k], name[k:]
            if a != b and self._known(a) and self._known(b):  # "gg" is a typo of g
                return f"write {a}*{b}: a product needs '*'"
        # another body's reactions are understood but never suggested: they are not on
        # this free body
        known = [n for n in (*self.accelerations, *self.own_reactions, *self.values)
                 if n not in self.absent]
        hint = did_you_mean(name, known)
        if not hint:
            hint = did_you_mean(name, [a for a in self.aliases if a.isascii()])
            close = hint.split("'")[1] if hint else ""
            if close:
                hint = f"did you mean '{self.aliases[close]}'?"
        return hint

    def _known(self, name: str) -> bool:
        name = self.aliases.get(name, name)
        return name in self.values or name in self._unknown_set

    @cached_property
    def _unknown_set(self) -> frozenset[str]:
        return frozenset(self.unknowns)  # once: a model may have thousands of reactions

    def summary(self) -> str:
        """The canonical names in one line (for error messages): at most `SUMMARY_NAMES`
        of them, and how many more (a large model's Lagrange equations have thousands).

        Returns
        -------
        str
        """
        return self._summary

    @cached_property
    def _summary(self) -> str:  # once: every unknown name's message repeats it
        shown = list(self.accelerations)
        own = self.own_reactions
        if own:
            shown.append(", ".join(own[:6]) + (" ..." if len(own) > 6 else ""))
        shown += [n for n in self.values if "." not in n and n != "pi"]
        return name_list(shown, SUMMARY_NAMES)


def name_gravity(model: Model, values: dict[str, float], absent: dict[str, str]) -> None:
    """`g` in an equation: |gravity| (m/s^2) into `values`, or, for a model without
    gravity, why the name means nothing here into `absent`."""
    gravity = float(np.linalg.norm(model.gravity))
    if gravity > 0:
        values["g"] = gravity
    else:
        absent["g"] = "this model has no gravity, so 'g' stands for nothing here"


def joints_of(model: Model, i: int) -> np.ndarray:
    """Indices of the joints that have body `i` as parent or child, in model order (from
    the joint table's arrays: a body's vocabulary and rows cost its own joints, not the
    model's)."""
    jt = model.joint_table
    return np.flatnonzero((jt.parent == i) | (jt.child == i))


def vocabulary(model: Model, state: State, body: str) -> Vocabulary:
    """The vocabulary of `body` at `state`.

    Parameters
    ----------
    model : Model
        The model.
    state : State
        Where the numbers (angular velocity, angle, time-varying known reactions) are
        taken.
    body : str
        A body of the model.

    Returns
    -------
    Vocabulary
        Its unknowns, numbers and aliases.
    """
    i = model.index[body]
    planar = model.dimension == cv.PLANAR
    particle = bool(model.particle[i])
    known = model.known_reactions_at(state.t)
    values: dict[str, float] = {"m": float(model.mass[i]), "pi": float(np.pi)}
    absent: dict[str, str] = {}
    name_gravity(model, values, absent)
    aliases = dict(_ALIASES_BOTH)
    aliases.update(_ALIASES_PLANAR if planar else _ALIASES_SPATIAL)
    accelerations: tuple[str, ...] = PLANAR_ACCELERATIONS if planar else SPATIAL_ACCELERATIONS
    J = model.J[i]
    if planar:
        values["theta"] = float(_planar_angle(state.W_R_B[i]))
        absent["a_z"] = "a planar body has no a_z (its rows are x, y and theta)"
        for k in (1, 2, 3):
            absent[f"alpha_{k}"] = ("a planar body has one angular acceleration: alpha "
                                    "(about z)")
            absent[f"w_{k}"] = "a planar body has one angular velocity: w (about z)"
            absent[f"I_{k}"] = "a planar body has one moment of inertia: I_G"
    else:
        absent["alpha"] = ("a spatial body has three angular accelerations, about its body "
                           "axes: alpha_1, alpha_2, alpha_3")
        absent["w"] = ("a spatial body has three angular velocity components, along its "
                       "body axes: w_1, w_2, w_3")
        absent["I_G"] = absent["I"] = (
            "a spatial body has an inertia tensor, not one inertia: I_1, I_2, I_3 (principal "
            "moments) or its entries I_11 ... I_33")
    if particle:
        accelerations = accelerations[:2] if planar else accelerations[:3]
        why = f"{body} is a particle (inertia 0): it has no rotation rows"
        for name in ("alpha", "alpha_1", "alpha_2", "alpha_3", "I_G", "I_1", "I_2", "I_3",
                     "w", "w_1", "w_2", "w_3", "theta"):
            absent[name] = why
        values.pop("theta", None)
    elif planar:
        values["I_G"] = float(J[2, 2])
        values["w"] = float(state.omega[i, 2])
    else:
        for j in range(3):
            values[f"w_{j + 1}"] = float(state.omega[i, j])
            for k in range(3):
                values[f"I_{j + 1}{k + 1}"] = float(J[j, k])
        if np.count_nonzero(J - np.diag(np.diag(J))) == 0:
            for k in range(3):
                values[f"I_{k + 1}"] = float(J[k, k])
        else:
            for k in range(3):
                absent[f"I_{k + 1}"] = (
                    f"the inertia tensor of {body} is not diagonal in its body axes, so it "
                    "has no principal moments along them: use its entries I_11, I_12 ... "
                    "I_33")
    own = [model.joints[j] for j in joints_of(model, i)]
    for joint in own:
        if not particle:
            # I_O for the inertia about a pin: the course writes it I_G + m d²
            absent.setdefault(f"I_{joint.name}", (
                f"there is no name for the inertia about joint {joint.name}: write it "
                f"from I_G, as I_G + m*d^2 with d the distance from G to {joint.name}"
                if planar else
                f"there is no name for the inertia about joint {joint.name}: write "
                "moments about the mass centre, with I_1, I_2, I_3 or I_11 ... I_33"))
    reactions = tuple(r for r in model.reactions if r not in known) if known else \
        tuple(model.reactions)
    drivers = model.drivers
    touching = {label for j in joints_of(model, i).tolist()  # a driver's effort: a reaction
                for label in (*model.joints[j].labels,
                              *(drivers.labels_of(j) if drivers is not None else ()))}
    acting = tuple(r for r in reactions if r in touching)
    for label, value in known.items():
        values[label] = float(value)
    # the time, so that a load written as `mbody assemble --symbolic` defines it
    # (M_load = -60*exp(-90*t)) can be copied as it stands
    values["t"] = float(state.t)
    for sym in load_symbols(model, state, body):
        values.setdefault(sym.name, float(sym.value))
    return Vocabulary(body, model.dimension, tuple(accelerations), reactions, values,
                      {a: c for a, c in aliases.items() if a not in values},
                      {n: why for n, why in absent.items() if n not in values}, acting)


NEWTON_EULER_SCAN = 64
"""Most bodies whose vocabularies `newton_euler_bodies` makes (each costs the body's
joints and loads): enough to name the bodies of an equation that names a reaction, or
the first few of a large model's for one that names none."""


def newton_euler_bodies(model: Model, state: State, names: list[str], most: int = 5,
                        cache: dict[str, Vocabulary] | None = None) -> tuple[list[str], bool]:
    """The bodies whose Newton-Euler equations may use every one of `names` (a reaction
    only when it acts on the body): what an entry without ``body:`` may have been meant
    for.

    Parameters
    ----------
    model : Model
        The model.
    state : State
        Its state (a vocabulary's numbers).
    names : list of str
        Names as written in an equation.
    most : int
        How many bodies to find at most.
    cache : dict, optional
        Vocabularies by body, kept between calls.

    Returns
    -------
    bodies : list of str
        Those bodies, in model order, at most `most`.
    more : bool
        Whether other bodies may read them too: `most` were found before the end, or
        only the first `NEWTON_EULER_SCAN` of the bodies to look at were looked at.
    """
    cache = {} if cache is None else cache
    used = [model.reaction_index[n] for n in names if n in model.reaction_index]
    if used:  # only the bodies every named reaction acts on
        rt = model.reaction_table
        bodies = set.intersection(*({int(b) for b in (rt.parent[c], rt.child[c]) if b >= 0}
                                    for c in used))
        candidates = sorted(bodies)
    else:
        candidates = list(range(model.n))
    found: list[str] = []
    for k, i in enumerate(candidates[:NEWTON_EULER_SCAN]):
        body = model.body_names[i]
        if body not in cache:
            cache[body] = vocabulary(model, state, body)
        if all(_reads(cache[body], n) for n in names):
            found.append(body)
            if len(found) == most:
                return found, k + 1 < len(candidates)
    return found, len(candidates) > NEWTON_EULER_SCAN


def _reads(vocab: Vocabulary, name: str) -> bool:
    """Whether `name` is a name of `vocab`'s body (another body's reaction is not)."""
    canonical = vocab.canonical(name)
    if canonical is None:
        return False
    return canonical in vocab.values or canonical in vocab.accelerations \
        or canonical in vocab.own_reactions


def _planar_angle(W_R_B: np.ndarray) -> float:
    """θ of a planar body from its rotation about z."""
    return float(np.arctan2(W_R_B[1, 0], W_R_B[0, 0]))
