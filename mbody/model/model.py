"""`Model` (what the file says, as arrays) and `State` (where the bodies are and how fast).

A `Model` is immutable and holds no state: masses ``(n,)``, inertia tensors ``(n, 3, 3)``
in body axes, and the loads and joints as tables of index arrays, so that everything
downstream is vectorised over bodies. Planar bodies are stored as spatial ones in the
world x-y plane (see `conventions`).

`load` and `loads` read a file into a `Model`. The tables are in `mbody.model.tables`, the
records (`Body`, `Load`, `Joint`) in `mbody.model.records`, and what builds them from a
validated specification in `mbody.model.build`; this module re-exports their public names.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from numbers import Real
from typing import Any

import numpy as np

from mbody import conventions as cv
from mbody.errors import Issue, MbodyError, MbodyTypeError, ModelError, wrong_type
from mbody.model.build import joint_tables, located_loads, point_loads
from mbody.model.drivers import DriverTable, driver_table
from mbody.model.expressions import Expression
from mbody.model.fast import fast_spec
from mbody.model.graph import body_graph
from mbody.model.loader import Document, check_source, decode, load_text, read_file, refuse_xml
from mbody.model.records import Body, BodyRecords, Joint, Load, Records
from mbody.model.reprs import count, name_list
from mbody.model.source import Source
from mbody.model.tables import ForceTable, JointTable, ReactionTable, SpringTable, readonly
from mbody.model.validate import JointSpecTable, Spec, validate
from mbody.model.values import apply as apply_values
from mbody.model.values import edits, entry_names, validate_edited
from mbody.util.spatial import quat_to_matrix

__all__ = ["Body", "BodyRecords", "ForceTable", "Joint", "JointTable", "Load", "Model",
           "ReactionTable", "Records", "SpringTable", "State", "count", "load", "loads"]


@dataclass(frozen=True)
class State:
    """Positions and velocities of all bodies; every array has a leading body axis.

    Parameters
    ----------
    position : (n, 3) array
        Mass centres, world axes (m).
    quaternion : (n, 4) array
        Body-to-world rotations ``W_R_B`` as unit quaternions, ``[w, x, y, z]``.
    velocity : (n, 3) array
        Mass-centre velocities, world axes (m/s).
    omega : (n, 3) array
        Angular velocities, body axes (rad/s).
    t : float, optional
        Time (s), for loads and known reactions that vary in time.

    Raises
    ------
    MbodyError
        An array of another shape than (n, k) (one row per body, the same n in all four),
        or a `t` that is not a finite number (`MbodyTypeError` for text or a bool, an
        array of things that are not numbers). Lists and arrays of other number types
        are converted to float arrays; a float array is kept as given (not copied).

    Notes
    -----
    The values themselves (finite numbers, quaternions that are not 0) are checked
    against a model where a state enters mbody (`mbody.model.arguments.checked_state`).
    """

    position: np.ndarray
    quaternion: np.ndarray
    velocity: np.ndarray
    omega: np.ndarray
    t: float = 0.0

    def __post_init__(self) -> None:
        x, q, v, w = self.position, self.quaternion, self.velocity, self.omega
        f = _FLOAT64  # the usual state: float arrays of the right shapes, kept as they are
        if not (type(x) is type(q) is type(v) is type(w) is np.ndarray
                and x.dtype is q.dtype is v.dtype is w.dtype is f and x.ndim == 2
                and x.shape[1] == 3 and q.shape == (len(x), 4) and v.shape == x.shape
                and w.shape == x.shape):
            self._convert()
        t = self.t
        if type(t) is not float:
            if isinstance(t, bool) or not isinstance(t, Real):
                raise MbodyTypeError(f"State: t must be a number of seconds, got "
                                     f"{type(t).__name__} {t!r}")
            t = float(t)
            object.__setattr__(self, "t", t)
        if not math.isfinite(t):
            raise MbodyError(f"State: t must be a finite number of seconds, got {t!r}")

    def _convert(self) -> None:
        """The arrays as float arrays (lists, other number types), or an error that names
        the one of the wrong shape."""
        n = -1
        for name, width in _STATE_ARRAYS:
            value = getattr(self, name)
            if type(value) is not np.ndarray or value.dtype is not _FLOAT64:
                value = _float_array(value, name, f"(n, {width})")
                object.__setattr__(self, name, value)  # frozen: set once, here
            shape = value.shape
            if len(shape) != 2 or shape[1] != width:
                raise MbodyError(f"State: {name} must be an (n, {width}) array, one row per "
                                 f"body, got shape {shape}"
                                 + (f" (one body: [[{', '.join(['...'] * width)}]])"
                                    if shape == (width,) else ""))
            if n < 0:
                n = shape[0]
            elif shape[0] != n:
                raise MbodyError(f"State: position has {n} rows (bodies), {name} "
                                 f"{shape[0]}: one row per body in each")

    @cached_property
    def W_R_B(self) -> np.ndarray:
        """(n, 3, 3) body-to-world rotation matrices."""
        return quat_to_matrix(self.quaternion)

    def replace(self, **changes: Any) -> State:
        """A copy with some fields changed, e.g. ``state.replace(t=1.0)``.

        Parameters
        ----------
        **changes
            Field name -> new value.

        Returns
        -------
        State
        """
        return replace(self, **changes)

    @classmethod
    def planar(cls, position: np.ndarray, angle: np.ndarray, velocity: np.ndarray,
               angular_velocity: np.ndarray, t: float = 0.0) -> State:
        """A planar state: bodies in the world x-y plane, turning about z.

        One body may be written without its row: ``State.planar([0, -0.5], 0.3, [0, 0],
        0.0)`` (a scalar `angle`, two numbers for `position` and `velocity`). A single
        number for `position`, `velocity` or `angular_velocity` is every body's (``0``:
        at rest).

        Parameters
        ----------
        position : (n, 2) array
            Mass centres, world x and y (m).
        angle : (n,) array
            Rotation angles about z (rad).
        velocity : (n, 2) array
            Mass-centre velocities, world x and y (m/s).
        angular_velocity : (n,) array
            θ̇ about z (rad/s).
        t : float, optional
            Time (s).

        Returns
        -------
        State

        Raises
        ------
        MbodyError
            The arrays disagree on the number of bodies (the message names them and their
            shapes), or one is not of the shape above.
        """
        theta, position, velocity, angular_velocity = _planar_arrays(
            angle, position, velocity, angular_velocity)
        n = len(theta)
        pos = np.zeros((n, 3))
        pos[:, :2] = position
        vel = np.zeros((n, 3))
        vel[:, :2] = velocity
        q = np.zeros((n, 4))
        q[:, 0] = np.cos(theta / 2)
        q[:, 3] = np.sin(theta / 2)
        om = np.zeros((n, 3))
        om[:, 2] = angular_velocity
        return cls(pos, q, vel, om, t)

    def __repr__(self) -> str:  # the dataclass's would print four (n, k) arrays
        return (f"<State of {count(len(self.position), 'body', 'bodies')} at t = {self.t:g} s; "
                ".position, .quaternion, .velocity, .omega, .replace(t=...)>")


_STATE_ARRAYS = (("position", 3), ("quaternion", 4), ("velocity", 3), ("omega", 3))
"""A `State`'s arrays and their widths: each (n, width), one row per body."""
_FLOAT64 = np.dtype(float)


def _float_array(value: Any, name: str, shape: str, where: str = "State") -> np.ndarray:
    """`value` as a float array, or an `MbodyTypeError` naming the argument (text, None or
    objects that are not numbers)."""
    if isinstance(value, str | bytes):
        raise MbodyTypeError(f"{where}: {name} must be an {shape} array of numbers, got "
                             f"{type(value).__name__} {value!r}")
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise MbodyTypeError(f"{where}: {name} must be an {shape} array of numbers, got "
                             f"{type(value).__name__} ({exc})") from None


def _planar_arrays(angle: Any, position: Any, velocity: Any, angular_velocity: Any
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """`State.planar`'s arguments as float arrays (n,), (n, 2), (n, 2), (n,), n from
    `angle`: a body written without its row and a single number for every body taken,
    any other shape refused with the argument named."""
    a = angle
    if (type(a) is np.ndarray and a.dtype is _FLOAT64 and a.ndim == 1
            and type(position) is type(velocity) is type(angular_velocity) is np.ndarray
            and position.dtype is velocity.dtype is angular_velocity.dtype is _FLOAT64
            and position.shape == velocity.shape == (len(a), 2)
            and angular_velocity.shape == a.shape):  # the usual call: nothing to convert
        return a, position, velocity, angular_velocity
    theta = _float_array(angle, "angle", "(n,)", "State.planar")
    if theta.ndim > 1:
        raise MbodyError(f"State.planar: angle must be an (n,) array, one angle per "
                         f"body, got shape {theta.shape}")
    theta = theta.reshape(-1)
    n = len(theta)
    parts = []
    for name, value, width in (("position", position, 2), ("velocity", velocity, 2),
                               ("angular_velocity", angular_velocity, 0)):
        want = (n, width) if width else (n,)
        x = _float_array(value, name, "(n, 2)" if width else "(n,)", "State.planar")
        if x.ndim == 0:  # one number for every body (0: at rest), as numpy broadcasts
            x = np.broadcast_to(x, want)
        elif n == 1 and x.shape == want[1:]:  # one body written without its row
            x = x.reshape(want)
        if x.shape != want:
            if x.ndim == len(want) and x.shape[1:] == want[1:]:
                raise MbodyError(f"State.planar: {name} has {x.shape[0]} rows, angle "
                                 f"{n}: one per body in each")
            raise MbodyError(f"State.planar: {name} must be a {want} array (one "
                             f"{'row' if width else 'value'} per body; angle gives "
                             f"{n}), got shape {x.shape}")
        parts.append(x)
    return theta, parts[0], parts[1], parts[2]


@dataclass(frozen=True, eq=False)
class Model:
    """A validated multibody model: bodies, applied loads and joints, as arrays.

    Made by `mbody.load`; immutable, and holds no state but the file's `initial` one.

    Parameters
    ----------
    name, file, description : str
        The model's name, the file it came from, its description.
    dimension : int
        2 (planar) or 3 (spatial).
    body_names : tuple of str
        The stacking order (file order).
    mass : (n,) array
        kg.
    J, J_inv : (n, 3, 3) arrays
        Inertia tensors about the mass centres, body axes (kg m²), and their inverses.
    gravity : (3,) array
        World axes (m/s²).
    initial : State
        The state written in the file.
    bodies : mapping of str to Body
        Each body by name, in the stacking order (each record is made on first use);
        ``bodies[0]`` is the first body too.
    loads : sequence of Load
        The applied loads, in file order; ``loads["push"]`` finds one by name.
    joints : sequence of Joint
        The joints, in file order (records made on first use); ``joints["A"]`` finds one
        by name.
    forces, springs : ForceTable, SpringTable
        The loads as arrays, for the vectorised sums.
    reaction_table : ReactionTable
        One row per reaction component (a column of G), for the vectorised columns.
    known_reactions : dict of str to float
        Reaction values given in the file (at t = 0).
    warnings : tuple of Issue, optional
        What validation noticed without refusing the file.
    known_expressions : dict, optional
        Known reaction values that vary in time (label -> expression of t).
    drivers : DriverTable, optional
        Joint coordinates prescribed as functions of time, whose efforts are unknowns.
    file_state : State, optional
        The file's own state when `initial` is the assembled one (None otherwise).
    source : Source, optional
        What the model was read from and the values set since (`with_values`).
    """

    name: str
    file: str
    dimension: int
    body_names: tuple[str, ...]
    mass: np.ndarray
    J: np.ndarray
    J_inv: np.ndarray
    gravity: np.ndarray
    initial: State
    bodies: Mapping[str, Body]
    loads: Sequence[Load]
    joints: Sequence[Joint]
    forces: ForceTable
    springs: SpringTable
    reaction_table: ReactionTable
    known_reactions: dict[str, float]
    description: str = ""
    warnings: tuple[Issue, ...] = field(default_factory=tuple)
    known_expressions: dict[str, Expression] = field(default_factory=dict)
    """Known reaction values that vary in time (label -> expression of t)."""
    drivers: DriverTable | None = None
    """Joint coordinates prescribed in time (`mbody.model.drivers`); their efforts are the
    last components of `reaction_table` (labels ``<driver>.M`` or ``.F``)."""
    file_state: State | None = None
    """The state the file wrote when `initial` is the assembled one (`mbody.load` moves the
    bodies onto their joints and drivers when the file gives joint points per body or
    drivers: `mbody.solve.kinematics.assembled`); None when `initial` is the file's."""
    source: Source | None = None
    """What the model was read from, and the values set since (`with_values`); None for a
    model built from a `Spec` directly."""

    def __repr__(self) -> str:  # the dataclass's would print every array (2-9 KB)
        kind = "planar" if self.dimension == cv.PLANAR else "spatial"
        bodies = name_list(self.body_names)
        return (f"<Model {self.name!r}: {kind}, {count(self.n, 'body', 'bodies')} "
                f"({bodies}), {count(len(self.loads), 'load')}, "
                f"{count(len(self.joints), 'joint')}, "
                f"{count(len(self.reactions), 'reaction component')}; mbody.assemble(model) "
                "for its equations>")

    def known_reactions_at(self, t: float) -> dict[str, float]:
        """The known reaction values at a time.

        Parameters
        ----------
        t : float
            Time (s); `known_reactions` holds t = 0.

        Returns
        -------
        dict of str to float
            Label -> value (N or N m).
        """
        if not self.known_expressions:
            return dict(self.known_reactions)
        return {**self.known_reactions,
                **{k: float(e(t)) for k, e in self.known_expressions.items()}}

    # -- sizes and labels --------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of bodies."""
        return len(self.body_names)

    @property
    def rows_per_body(self) -> int:
        """Rows of a rigid body in the stacked system: 3 planar, 6 spatial."""
        return cv.rows_per_body(self.dimension)

    @cached_property
    def particle(self) -> np.ndarray:
        """(n,) True for the point masses (`inertia: 0`)."""
        if isinstance(self.bodies, BodyRecords):  # without making every record
            return self.bodies.particle.copy()
        return np.array([self.bodies[b].particle for b in self.body_names], dtype=bool)

    @cached_property
    def has_particles(self) -> bool:
        """Whether any body is a point mass (translation rows only)."""
        return bool(self.particle.any())

    @cached_property
    def all_coordinates(self) -> list[str]:
        """The solver's uniform rows: `rows_per_body` per body, particles included."""
        return cv.coordinate_labels(list(self.body_names), self.dimension)

    @cached_property
    def rows(self) -> np.ndarray:
        """Indices into `all_coordinates` of the rows shown (`coordinates`): a particle's
        rotation rows are dropped (they carry nothing: its ω stays 0)."""
        rpb = self.rows_per_body
        keep = np.ones((self.n, rpb), dtype=bool)
        keep[self.particle, cv.rows_per_body(self.dimension) - (1 if self.dimension
                                                                   == cv.PLANAR else 3):] = False
        return np.flatnonzero(keep.reshape(-1))

    @cached_property
    def coordinates(self) -> list[str]:
        """Row labels of the stacked equations (a particle has translation rows only)."""
        if not self.has_particles:
            return self.all_coordinates
        full = self.all_coordinates
        return [full[i] for i in self.rows]

    def body_rows(self, i: int) -> np.ndarray:
        """Where one body's equations are in the stacked system.

        Parameters
        ----------
        i : int
            The body's index (`Model.index`).

        Returns
        -------
        (k,) int array
            Indices into `coordinates` of its rows (3 planar, 6 spatial, fewer for a
            particle).
        """
        if not self.has_particles:
            rpb = self.rows_per_body
            return np.arange(i * rpb, (i + 1) * rpb)
        rpb = self.rows_per_body
        return np.flatnonzero((self.rows >= i * rpb) & (self.rows < (i + 1) * rpb))

    @cached_property
    def reactions(self) -> list[str]:
        """Reaction labels, the column order of G (do not modify the list)."""
        return list(self.reaction_table.labels)

    @cached_property
    def minv6(self) -> np.ndarray | None:
        """(n, 6) diagonal of M⁻¹ per body [1/m ×3, 1/J11, 1/J22, 1/J33] when every
        inertia tensor is diagonal in body axes (principal axes given); else None."""
        off = self.J - np.einsum("nii->ni", self.J)[:, :, None] * np.eye(3)
        if np.any(off):
            return None
        out = np.empty((self.n, 6))
        out[:, :3] = 1.0 / self.mass[:, None]
        out[:, 3:] = 1.0 / np.einsum("nii->ni", self.J)
        return out

    @cached_property
    def joint_table(self) -> JointTable:
        """One row per joint: what its reaction components share (`JointTable`)."""
        return self.reaction_table.per_joint

    @cached_property
    def reaction_index(self) -> dict[str, int]:
        """reaction label -> column of G."""
        return {r: i for i, r in enumerate(self.reaction_table.labels)}

    @cached_property
    def index(self) -> dict[str, int]:
        """Body name -> its index in the stacking order."""
        return {n: i for i, n in enumerate(self.body_names)}

    @cached_property
    def graph(self):  # -> networkx.MultiGraph; imported lazily, it is slow to import
        """The body/joint graph: bodies and ``ground`` as nodes, joints as edges."""

        return body_graph(self)

    def with_values(self, values: Mapping[str, Any]) -> Model:
        """The model with some of the file's values changed, read and checked again.

        Parameters
        ----------
        values : mapping of str to value
            Path -> what the file would hold there: ``{"bodies.rod.mass": 2.0,
            "drivers.motor.speed": "100 rpm", "bodies.rod.position.1": 0.05}``. A path is
            ``bodies.<name>.<key>``, ``loads.<name>.<key>``, ``joints.<name>.<key>``,
            ``drivers.<name>.<key>`` or ``gravity``, then an index or key inside a list
            or mapping (`mbody.model.values`). An MJCF or URDF model's paths are those of
            its YAML form (``mbody convert``).

        Returns
        -------
        Model
            A new model, as `mbody.load` would give for the file with those values: every
            rule of the file checked, the bodies moved onto their joints and drivers when
            the file asks for it. This model is unchanged.

        Raises
        ------
        ModelError
            A path that names nothing in the file (with a did-you-mean), or a value the
            file could not hold, at the line of its entry and naming its path.
        """
        model = self.edited(values)
        finish = model.source.finish if model.source is not None else None
        return finish(model) if finish is not None else model

    def edited(self, values: Mapping[str, Any]) -> Model:
        """`with_values` before its last step: the file read again with the values set and
        checked, the model built, but the bodies not yet moved onto their joints and
        drivers (``model.source.finish``, which `mbody.load` takes). For a caller that
        does that step itself (`mbody.solve.family`, in the compiled core).

        Parameters
        ----------
        values : mapping of str to value
            As `with_values`.

        Returns
        -------
        Model
        """
        src = self.source
        if src is None:
            raise MbodyError(f"model {self.name!r} was built from a Spec, not read from a file "
                             "or a dictionary: there is no document to set values in (use "
                             "mbody.load)")
        given = tuple((str(k), v) for k, v in values.items())
        doc = src.read()
        names = entry_names(self)
        apply_values(doc, edits(doc, src.values, names))
        changes = edits(doc, given, names)
        apply_values(doc, changes)
        return _build(validate_edited(doc, changes), src.with_values(given))

    @classmethod
    def from_spec(cls, spec: Spec, source: Source | None = None) -> Model:
        """Build the arrays from a validated specification (what `load` does last).

        Parameters
        ----------
        spec : Spec
            The output of `mbody.model.validate.validate` (or of an MJCF or URDF import).
        source : Source, optional
            What the specification was read from (`Model.source`: what `with_values`
            edits); None for a specification built in code.

        Returns
        -------
        Model
        """
        return _build(spec, source)

    def _repr_html_(self) -> str:  # notebook display: summary tables and the graph
        from mbody.present.rich import model_html  # a display hook (tools/check_imports.py)

        return model_html(self)


def load(source: str | os.PathLike[str] | dict, *, max_bytes: int | None = None) -> Model:
    """Read, validate and build a model from a YAML file or a dict, at the file's state
    (`mbody.load` reads MJCF and URDF too, and moves a model whose file asks for it onto
    its joints and drivers).

    Parameters
    ----------
    source : str, os.PathLike or dict
        A path to an mbody YAML model file; or a dict with a YAML file's content (for
        scripts).
    max_bytes : int, optional
        The largest file read (default `mbody.util.budget.MAX_BYTES`, 32 MiB, or the
        command line's ``--max-bytes``); a larger file is refused before it is read.
        Raise it for very large models (a 100 000-body file is about 80 MB).

    Returns
    -------
    Model

    Raises
    ------
    mbody.ModelError
        Listing every problem, each with its file, line and column; or `source` is YAML
        text rather than a path (`loads` reads text).
    mbody.errors.MbodyTypeError
        `source` is neither a path nor a dict (a `TypeError` too), or `max_bytes` is not a
        whole number.
    """
    max_bytes = check_source(source, max_bytes, "mbody.model.load")
    if isinstance(source, dict):
        doc = Document(source, "<dict>")
        return _build(validate(doc), Source("<dict>", document=dataclasses.replace(
            doc, data=copy.deepcopy(source))))
    text = read_file(source, max_bytes)
    refuse_xml(text, str(source))
    spec = fast_spec(text, str(source)) or validate(load_text(text, str(source)))
    kept = Source.of_text(text, str(source))
    del text  # before the arrays are built: the text is the largest thing held (unless kept)
    return _build(spec, kept)


def from_source(source: Source) -> Model:
    """The model a `Source` describes: its document read again, with its values set and
    its finishing step taken (what a sweep's worker builds from what the command read).

    Parameters
    ----------
    source : Source
        `Model.source` of a model.

    Returns
    -------
    Model
        Equal to the model the source came from.
    """
    doc = source.read()
    bare = _build(validate_edited(doc, []), dataclasses.replace(source, values=()))
    if source.values:
        return bare.with_values(dict(source.values))
    return source.finish(bare) if source.finish is not None else bare


def loads(text: str | bytes, file: str = "<string>") -> Model:
    """Like `load`, from YAML text.

    Parameters
    ----------
    text : str or bytes
        The model file's content (bytes: UTF-8, as a file is read).
    file : str, optional
        The name used in error messages.

    Returns
    -------
    Model

    Raises
    ------
    mbody.ModelError
        Listing every problem, each with its file, line and column.
    mbody.errors.MbodyTypeError
        `text` is neither text nor bytes (a path goes to `load`).

    Notes
    -----
    A large, regular file (block YAML as ``yaml.dump`` writes it) is read and checked in
    bulk (`mbody.model.fast`); anything that path does not handle, and every file with a
    problem, goes through the located path, which reports each problem where it is.
    """
    text = model_text(text, file)
    refuse_xml(text, file)
    spec = fast_spec(text, file)
    if spec is None:
        spec = validate(load_text(text, file))
    return _build(spec, Source.of_text(text, file, from_file=False))


_MODEL_SUFFIXES = (".yaml", ".yml", ".xml", ".mjcf", ".urdf")


def model_text(text: object, file: str) -> str:
    """`loads`' `text` as a str: bytes decoded as UTF-8 (as a file is read); a path, or
    anything but text, refused with what `loads` takes (a path is `load`'s)."""
    if isinstance(text, str):
        if "\n" not in text and text.strip().lower().endswith(_MODEL_SUFFIXES):
            # a scalar is no model anyway: say what was meant rather than "expected a
            # model mapping, got the text 'models/pendulum.yaml'"
            raise ModelError([Issue(file, 0, 0, "text", "this looks like a path to a model "
                                    "file, not its text", "use mbody.load(path)")])
        return text
    if isinstance(text, bytes | bytearray):
        return decode(bytes(text), file)
    hint = ("a path goes to mbody.load(path)" if isinstance(text, os.PathLike)
            else "an open file's text is f.read()" if hasattr(text, "read") else "")
    raise wrong_type("text", "a model file's YAML text (str, or UTF-8 bytes)", text, hint)


def _build(spec: Spec, source: Source | None = None) -> Model:
    t = spec.table()
    n = len(t.names)
    names = t.names
    # name -> index, for the located path's records (the fast path's tables hold indices)
    idx = {nm: i for i, nm in enumerate(names)} if spec.loads or spec.joints else {}
    mass = readonly(t.mass)
    J = readonly(t.inertia.reshape(n, 3, 3))
    J_inv = np.linalg.inv(J)
    initial = State(readonly(t.position.reshape(n, 3)), readonly(t.quaternion.reshape(n, 4)),
                    readonly(t.velocity.reshape(n, 3)), readonly(t.omega.reshape(n, 3)))
    bodies = BodyRecords(names, mass, J, t.shape, t.color, t.particle)

    loads: Sequence[Load]
    if spec.load_table is not None:
        loads, forces = point_loads(spec.load_table, names)
    else:
        loads, forces = located_loads(spec.loads, idx)
    sp = [ld for ld in spec.loads if ld.type == "spring"]
    springs = SpringTable(
        tuple(ld.name for ld in sp),
        np.array([idx.get(ld.bodies[0], -1) for ld in sp], dtype=np.intp),
        np.array([idx.get(ld.bodies[1], -1) for ld in sp], dtype=np.intp),
        readonly(np.array([ld.at[0] for ld in sp]).reshape(-1, 3)),
        readonly(np.array([ld.at[1] for ld in sp]).reshape(-1, 3)),
        readonly(np.array([ld.stiffness for ld in sp], dtype=float)),
        readonly(np.array([ld.rest_length for ld in sp], dtype=float)),
        readonly(np.array([ld.damping for ld in sp], dtype=float)),
    )

    js = spec.joint_table
    if js is None:
        js = JointSpecTable.from_specs(spec.joints, idx)
    q = initial.quaternion  # a planar body's angle about z, for its drivers' offsets
    drivers = driver_table(spec.drivers, {nm: j for j, nm in enumerate(js.names)},
                           spec.dimension, (js.parent, js.child),
                           2.0 * np.arctan2(q[:, 3], q[:, 0]))
    joints, table = joint_tables(spec.dimension, js, names, initial, t.particle, drivers)
    return Model(spec.name, spec.file, spec.dimension, names, mass, J, readonly(J_inv),
                 readonly(spec.gravity), initial, bodies, loads, joints, forces, springs,
                 table, dict(spec.reactions), spec.description, tuple(spec.warnings),
                 dict(spec.reaction_expressions), drivers, source=source)
