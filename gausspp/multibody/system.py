"""``gp.Multibody``: a machine described as bodies and joints, made into a :class:`gausspp.Model`.

.. code-block:: python

    mb = gp.Multibody(gravity=(0.0, -9.81))                  # two numbers: planar; three: spatial
    crank = mb.body("crank", mass=1.0, inertia=1 / 12, at=(0.0, 0.5), angle=np.pi / 2)
    mb.revolute("ground-crank", crank, (-0.5, 0.0), None, (0.0, 0.0))
    ...
    model = mb.model()
    q0, v0 = mb.assemble(fix={"crank.θ": np.pi / 2}, rates={"crank.θ̇": -1.0})

Bodies (:mod:`.bodies`) give the mechanism (:mod:`.front_end`: ``A`` constant and block diagonal, gravity, the
spatial bodies' unit quaternions kept by their kinematics); joints (:mod:`.joints`) give named holonomic rows.
A closed loop is just more joints: rows that depend on each other are the general Gauss step's business (the
redundant rows are found and the motion is the same). Any joint row takes a realization; :meth:`Multibody.motor`
keeps a relative angle on a prescribed law by a torque between the two bodies (a servo-constraint).

:meth:`Multibody.assemble` finds initial data on the joints from a partial specification — some coordinates and
some rates held at given values, the others moved as little as possible from the bodies' guesses (Gauss–Newton on
the rows, least-norm steps; the velocities by least squares on the rows' rates). :meth:`Multibody.drawing` draws
the bodies (each as segments from its centre to its joints' points) for :func:`gausspp.plot.animate`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InitialDataError, InputError, UnknownNameError
from ..model.constraints import Constraint, Holonomic
from ..model.model import Model
from ..model.realizations import Force, Realization
from . import joints as J
from .bodies import Body, planar_body, spatial_body, vector
from .front_end import Bodies

#: Gauss–Newton stops when every row is within this of zero (relative to the size of the configuration) ...
ASSEMBLY_TOL = 1e-14
#: ... or gives up after this many iterations.
ASSEMBLY_ITERATIONS = 60
#: A spatial body's orientation unless given: the identity quaternion ``(w, x, y, z)``.
UPRIGHT = (1.0, 0.0, 0.0, 0.0)


class Multibody:
    """Bodies and joints (module docstring). ``gravity``: two numbers for a planar machine, three for a spatial one."""

    def __init__(self, gravity: Any = (0.0, -9.81)) -> None:
        g = np.asarray(gravity, float)
        if g.shape not in ((2,), (3,)) or not np.all(np.isfinite(g)):
            raise InputError(f"Multibody: gravity must be 2 numbers (planar) or 3 (spatial), got {gravity!r}")
        self.gravity, self.planar = g, g.shape == (2,)
        self.dim = 2 if self.planar else 3
        self._bodies: dict[str, Body] = {}
        self._rows: list[tuple[str, J.Row, Realization | str | None]] = []
        self._extra: list[Constraint] = []
        self._ground_points: list[np.ndarray] = []
        self._friction: list[Any] = []
        self._mechanism: Bodies | None = None
        self._assembly: tuple[ca.Function, ...] | None = None  # built on first assemble, dropped on any change

    # -- bodies -----------------------------------------------------------------------------------------
    def body(
        self,
        name: str,
        mass: float,
        inertia: Any,
        at: Any,
        angle: float | None = None,
        orientation: Any = None,
        load: Callable[..., Any] | None = None,
    ) -> str:
        """Add a body; returns its name (what the joints take).

        Parameters
        ----------
        name : str
            Unique; the coordinates are named ``name.x``, ``name.θ`` … and the velocities ``name.ẋ``, ``name.ωx`` ….
        mass : float
            (kg), > 0.
        inertia : float, 3 numbers or (3, 3)
            Planar: the moment about the centre of mass (kg·m²). Spatial: principal moments or the tensor in body axes.
        at : 2 or 3 numbers
            The centre of mass (m): exact or a guess for :meth:`assemble`.
        angle : float
            Planar only: the body's angle (rad), exact or a guess; default 0.
        orientation : 4 numbers
            Spatial only: the unit quaternion ``(w, x, y, z)`` body → space, exact or a guess; default ``(1, 0, 0, 0)``.
        load : callable ``(r, R, v, t) -> (3,)`` or ``(6,)``, optional
            Applied force on the centre of mass (space axes) and torque (planar: a scalar; spatial: body axes).
        """
        if not isinstance(name, str) or not name:
            raise InputError(f"Multibody.body: name must be a non-empty string, got {name!r}")
        if name in self._bodies:
            raise InputError(f"Multibody.body: a body {name!r} exists already")
        self._check_pose(name, angle, orientation)
        made = (
            planar_body(name, mass, inertia, at, 0.0 if angle is None else angle, load)
            if self.planar
            else spatial_body(name, mass, inertia, at, UPRIGHT if orientation is None else orientation, load)
        )
        q_start = sum(b.nq for b in self._bodies.values())
        v_start = sum(b.nv for b in self._bodies.values())
        self._bodies[name] = replace(made, q_start=q_start, v_start=v_start, points=[])
        self._mechanism = self._assembly = None
        return name

    def _check_pose(self, name: str, angle: Any, orientation: Any) -> None:
        """A planar body takes ``angle=``, a spatial one ``orientation=``: the other is refused, naming the body."""
        wrong, kind, right = ("orientation", "planar", "angle") if self.planar else ("angle", "spatial", "orientation")
        if (orientation if self.planar else angle) is not None:
            raise InputError(
                f"Multibody.body {name!r}: {wrong}= is not read for a {kind} body (this machine's gravity has "
                f"{self.dim} numbers); give {right}= instead"
            )

    def _pair(self, kind: str, joint: str, a: str | None, b: str | None) -> tuple[Body, Body | None]:
        """A joint's two bodies: ``a`` a body, ``b`` another body or ``None`` (the ground), or an error naming the
        joint and the fix."""
        fix = f"the ground goes second: {kind}({joint!r}, {b!r}, <its point>, None, <the point in space>, ...)"
        A_ = self._moving(kind, joint, a, fix)
        if a == b:
            raise InputError(
                f"{kind} {joint!r}: joins body {a!r} to itself; join it to another body or to the ground (None)"
            )
        return A_, self._body(b, joint)

    def _moving(self, kind: str, joint: str, name: str | None, fix: str) -> Body:
        """The body ``name`` that ``joint`` moves, or an error naming the joint and ``fix`` (``None``, the ground,
        does not move)."""
        if name is None:
            raise InputError(f"{kind} {joint!r}: the ground (None) is given where a body is needed; {fix}")
        body = self._body(name, joint)
        assert body is not None  # a name's body, or UnknownNameError
        return body

    def _body(self, name: str | None, joint: str) -> Body | None:
        if name is None:
            return None
        if name not in self._bodies:
            raise UnknownNameError(f"joint {joint!r}: no body {name!r}; bodies: {list(self._bodies)}")
        return self._bodies[name]

    def _point(self, joint: str, value: Any) -> np.ndarray:
        return vector(f"joint {joint!r}", "point", value, self.dim)

    def _add(self, kind: str, name: str, rows: list[tuple[str, J.Row]], realization: Any = None) -> None:
        if not isinstance(name, str) or not name:
            raise InputError(f"Multibody.{kind}: name must be a non-empty string, got {name!r}")
        taken = {r[0] for r in self._rows}
        for suffix, fn in rows:
            full = f"{kind} {name} [{suffix}]"
            if full in taken:
                raise InputError(f"Multibody.{kind}: a joint {name!r} exists already")
            self._rows.append((full, fn, realization))
        self._assembly = None

    def _attach(self, a: Body, pa: np.ndarray, b: Body | None, pb: np.ndarray) -> None:
        a.points.append(pa)
        if b is None:
            self._ground_points.append(pb)
        else:
            b.points.append(pb)

    # -- joints -----------------------------------------------------------------------------------------
    def revolute(
        self, name: str, a: str, pa: Any, b: str | None, pb: Any, axis: Any = None, realization: Any = None
    ) -> None:
        """Pin the point ``pa`` of body ``a`` to the point ``pb`` of body ``b`` (``None``: the ground, ``pb`` in
        space). Spatial: also the hinge axis, ``axis`` in ``a``'s axes (and ``b``'s at the guess)."""
        A_, B_ = self._pair("revolute", name, a, b)
        pa_, pb_ = self._point(name, pa), self._point(name, pb)
        rows = J.coincide(A_, pa_, B_, pb_, self.dim)
        if self.planar and axis is not None:
            raise InputError(f"revolute {name!r}: a planar revolute turns about the plane's normal; give no axis")
        if not self.planar:
            if axis is None:
                raise InputError(f"revolute {name!r}: a spatial revolute needs its axis (in body {a!r}'s axes)")
            ea = J.unit(f"revolute {name!r}", axis, 3)
            rows += J.aligned(A_, ea, B_, J.relative_rotation(A_, B_).T @ ea)
        self._attach(A_, pa_, B_, pb_)
        self._add("revolute", name, rows, realization)

    def prismatic(self, name: str, a: str, pa: Any, b: str | None, pb: Any, axis: Any, realization: Any = None) -> None:
        """Let the point ``pb`` of ``b`` slide along the line through ``pa`` of ``a`` along ``axis`` (``a``'s axes),
        the relative rotation held at the guess."""
        A_, B_ = self._pair("prismatic", name, a, b)
        pa_, pb_ = self._point(name, pa), self._point(name, pb)
        e = J.unit(f"prismatic {name!r}", axis, self.dim)
        if self.planar:
            theta0 = float(A_.guess[2] - (0.0 if B_ is None else B_.guess[2]))
            rows = J.planar_prismatic(A_, pa_, B_, pb_, e, theta0)
        else:
            R0 = J.relative_rotation(A_, B_)
            u1, u2 = J.normals(e)
            rows = J.on_line(A_, pa_, B_, pb_, e) + J.aligned(A_, e, B_, R0.T @ e)
            rows.append(("twist", _twist(A_, B_, R0, u1, u2)))
        self._attach(A_, pa_, B_, pb_)
        self._add("prismatic", name, rows, realization)

    def spherical(self, name: str, a: str, pa: Any, b: str | None, pb: Any, realization: Any = None) -> None:
        """A ball joint: the two points coincide (spatial)."""
        self._spatial_only("spherical")
        A_, B_ = self._pair("spherical", name, a, b)
        pa_, pb_ = self._point(name, pa), self._point(name, pb)
        self._attach(A_, pa_, B_, pb_)
        self._add("spherical", name, J.coincide(A_, pa_, B_, pb_, 3), realization)

    def universal(
        self, name: str, a: str, pa: Any, b: str | None, pb: Any, axis_a: Any, axis_b: Any, realization: Any = None
    ) -> None:
        """A Hooke joint: the points coincide, ``axis_a`` (in ``a``) and ``axis_b`` (in ``b``) stay perpendicular."""
        self._spatial_only("universal")
        A_, B_ = self._pair("universal", name, a, b)
        pa_, pb_ = self._point(name, pa), self._point(name, pb)
        ea, eb = J.unit(f"universal {name!r}", axis_a, 3), J.unit(f"universal {name!r}", axis_b, 3)
        rows = J.coincide(A_, pa_, B_, pb_, 3)
        rows.append(("axes", lambda q, t: ca.dot(J.rotation(A_, q, 3) @ ca.DM(ea), J.rotation(B_, q, 3) @ ca.DM(eb))))
        self._attach(A_, pa_, B_, pb_)
        self._add("universal", name, rows, realization)

    def cylindrical(
        self, name: str, a: str, pa: Any, b: str | None, pb: Any, axis: Any, realization: Any = None
    ) -> None:
        """``pb`` of ``b`` on the line through ``pa`` of ``a`` along ``axis``, the axes parallel (slide and turn)."""
        self._spatial_only("cylindrical")
        A_, B_ = self._pair("cylindrical", name, a, b)
        pa_, pb_ = self._point(name, pa), self._point(name, pb)
        e = J.unit(f"cylindrical {name!r}", axis, 3)
        rows = J.on_line(A_, pa_, B_, pb_, e) + J.aligned(A_, e, B_, J.relative_rotation(A_, B_).T @ e)
        self._attach(A_, pa_, B_, pb_)
        self._add("cylindrical", name, rows, realization)

    def fixed(self, name: str, a: str, pa: Any, b: str | None, pb: Any, realization: Any = None) -> None:
        """Weld: the points coincide and the relative rotation is held at the guess (six rows; planar: three)."""
        A_, B_ = self._pair("fixed", name, a, b)
        pa_, pb_ = self._point(name, pa), self._point(name, pb)
        rows = J.coincide(A_, pa_, B_, pb_, self.dim)
        if self.planar:
            theta0 = float(A_.guess[2] - (0.0 if B_ is None else B_.guess[2]))
            rows.append(("angle", lambda q, t: J.angle(A_, q) - J.angle(B_, q) - theta0))
        else:
            rows += J.kept_rotation(A_, B_, J.relative_rotation(A_, B_), [(1, 2), (2, 0), (0, 1)])
        self._attach(A_, pa_, B_, pb_)
        self._add("fixed", name, rows, realization)

    def on_curve(self, name: str, a: str, pa: Any, f: Callable[..., Any], realization: Any = None) -> None:
        """The point ``pa`` of ``a`` on the curve ``f(point, t) = 0`` (planar) or surface (spatial): one row."""
        kind = "curve" if self.planar else "surface"
        A_ = self._moving(f"on-{kind}", name, a, "give the body whose point it holds")
        pa_ = self._point(name, pa)
        A_.points.append(pa_)
        self._add(f"on-{kind}", name, [("f", lambda q, t: f(A_.point(q, pa_), t))], realization)

    on_surface = on_curve

    def motor(
        self,
        name: str,
        a: str | None,
        b: str,
        law: Callable[[Any], Any],
        realization: Realization | str | None = None,
    ) -> None:
        """Keep ``θ_b − θ_a = law(t)`` (planar; ``a = None``: the ground) — a servo-constraint kept by a torque
        between the two bodies (``gp.Force`` along ``e_θb − e_θa``, Béghin's realization), unless ``realization``
        says otherwise."""
        if not self.planar:
            raise InputError("Multibody.motor: a spatial motor is not available; drive a revolute's angle in the plane")
        B_ = self._moving("motor", name, b, f"the ground goes first: motor({name!r}, None, <body>, law)")
        if a == b:
            raise InputError(f"motor {name!r}: turns body {b!r} against itself; give another body or the ground (None)")
        A_ = self._body(a, name)

        def torque_pair(q: Any, v: Any, t: Any) -> Any:  # +1 on θ_b, −1 on θ_a: the motor's torque on each body
            d = np.zeros(v.numel())
            d[B_.v_start + 2] = 1.0
            if A_ is not None:
                d[A_.v_start + 2] = -1.0
            return ca.DM(d)

        kept = Force(M=torque_pair) if realization is None else realization
        self._assembly = None
        self._extra.append(
            Holonomic(lambda q, t: J.angle(B_, q) - J.angle(A_, q) - law(t), name=f"motor {name}", realization=kept)
        )

    def spin(
        self, name: str, body: str, axis: Any, law: Callable[[Any], Any], realization: Realization | str | None = None
    ) -> None:
        """Keep a spatial body's angular velocity about ``axis`` (its body axes) at ``law(t)``: ``(ω, e) = Ω(t)`` — a
        servo-constraint on the velocities kept by a torque about that axis (``gp.Force`` along it, Béghin's
        realization) unless ``realization`` says otherwise; the flyball governor's prescribed spin."""
        self._spatial_only("spin")
        B_ = self._moving("spin", name, body, "give the body that spins")
        e = J.unit(f"spin {name!r}", axis, 3)

        def along(q: Any, v: Any, t: Any) -> Any:  # the torque's direction: about e on the body
            d = np.zeros(v.numel())
            d[B_.v_start + 3 : B_.v_start + 6] = e
            return ca.DM(d)

        kept = Force(M=along) if realization is None else realization
        self._assembly = None
        self._extra.append(
            Constraint(
                lambda q, v, t: ca.dot(v[B_.v_start + 3 : B_.v_start + 6], ca.DM(e)) - law(t),
                name=f"spin {name}",
                realization=kept,
            )
        )

    def _spatial_only(self, kind: str) -> None:
        if self.planar:
            raise InputError(f"Multibody.{kind}: a {kind} joint needs a spatial machine (gravity of three numbers)")

    # -- the model ----------------------------------------------------------------------------------------
    @property
    def mechanism(self) -> Bodies:
        """The bodies as one :class:`gausspp.Mechanism` (built on first use)."""
        if not self._bodies:
            raise InputError("Multibody: add bodies first (Multibody.body)")
        if self._mechanism is None:
            self._mechanism = Bodies(list(self._bodies.values()), self.gravity)
        return self._mechanism

    @property
    def constraints(self) -> list[Constraint]:
        """One :class:`gausspp.Holonomic` per joint row, then the motors and spins."""
        return [Holonomic(fn, name=name, realization=real) for name, fn, real in self._rows] + list(self._extra)

    def ground_contact(
        self, name: str, body: str, point: Any = None, *, mu: float, mu_static: float | None = None,
        radius: float = 0.0, normal: Any = None, height: float = 0.0, restitution: float = 0.0,
    ) -> None:  # fmt: skip
        """A point of ``body`` (``point`` from its centre of mass, body axes; default the centre) — with a sphere of
        ``radius`` around it — on the ground plane ``normal·x = height`` (``normal`` default: against gravity), a
        hard contact with Coulomb friction ``mu`` (:mod:`gausspp.multibody.ground`); :meth:`model` takes it."""
        from .ground import ground_contact

        if name in {c.name for c in self._friction}:
            raise InputError(f"Multibody.ground_contact: a contact {name!r} exists already")
        b = self._moving("ground_contact", name, body, "name a body added with Multibody.body")
        up = -self.gravity / np.linalg.norm(self.gravity) if np.any(self.gravity) else np.eye(self.dim)[-1]
        self._friction.append(
            ground_contact(
                b,
                name,
                np.zeros(self.dim) if point is None else point,
                up if normal is None else normal,
                height,
                radius,
                mu,
                mu_static,
                restitution,
            )  # fmt: skip
        )

    def model(self, **options: Any) -> Model:
        """The :class:`gausspp.Model` of the bodies and joints (``options`` as for ``gp.Model``), with the ground
        contacts (:meth:`ground_contact`) as its frictional contacts."""
        if self._friction:
            options["friction"] = [*self._friction, *options.get("friction", ())]
        return Model(self.mechanism, self.constraints, **options)

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        return tuple(self.mechanism.coordinate_names or ())

    @property
    def velocity_names(self) -> tuple[str, ...]:
        return tuple(self.mechanism.velocity_names or ())

    def guess(self) -> np.ndarray:
        """The bodies' coordinates as given (before :meth:`assemble`)."""
        return np.concatenate([b.guess for b in self._bodies.values()])

    # -- assembly -----------------------------------------------------------------------------------------
    def assemble(
        self,
        t: float = 0.0,
        fix: Mapping[str, float] | None = None,
        rates: Mapping[str, float] | None = None,
        q: Any = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Initial data on every joint row: ``(q0, v0)``.

        ``fix`` holds coordinates (``{"crank.θ": 1.2}``) and ``rates`` velocities (``{"crank.θ̇": -1.0}``, or by the
        coordinate's name where the velocity is its rate); the other coordinates move from the bodies' guesses (or
        from ``q``) by Gauss–Newton on the rows with least-norm steps, the other velocities solve the rows' rates by
        least squares (zero where nothing asks for motion). Raises :class:`gausspp.InitialDataError` if the rows
        cannot be met with what is held."""
        mech = self.mechanism
        names, vnames = list(self.coordinate_names), list(self.velocity_names)
        q_now = self.guess() if q is None else vector("Multibody.assemble", "q", q, len(names)).copy()
        held = _indices(fix or {}, names, "fix")
        for i, value in zip(held, (fix or {}).values(), strict=True):
            q_now[i] = float(value)
        free = [i for i in range(len(names)) if i not in held]
        if self._assembly is None:
            self._assembly = self._functions()
        g_fn, G_fn, Jv_fn, phi0_fn = self._assembly
        scale = 1.0 + float(np.max(np.abs(q_now)))
        for _ in range(ASSEMBLY_ITERATIONS):
            q_now = mech.normalize_array(q_now)
            g = np.array(g_fn(q_now, t)).ravel()
            if np.max(np.abs(g), initial=0.0) <= ASSEMBLY_TOL * scale:
                break
            G = np.array(G_fn(q_now, t))[:, free]
            q_now[free] -= np.linalg.lstsq(G, g, rcond=None)[0]
        else:
            g = np.array(g_fn(q_now, t)).ravel()
            worst = int(np.argmax(np.abs(g)))
            raise InitialDataError(
                f"Multibody.assemble: the joints cannot be met with {sorted(fix or {})} held — row "
                f"{self._row_names(positions=True)[worst]!r} is still {g[worst]:.3g} after {ASSEMBLY_ITERATIONS} "
                "iterations; "
                "change the held values or the bodies' guesses (at=, angle=)"
            )
        q_now = mech.normalize_array(q_now)
        v_now = np.zeros(len(vnames))
        rate_keys = {k: v for k, v in (rates or {}).items()}
        by_rate = _indices(rate_keys, [*vnames], "rates", aliases=self._rate_aliases())
        for i, value in zip(by_rate, rate_keys.values(), strict=True):
            v_now[i] = float(value)
        others = [i for i in range(len(vnames)) if i not in by_rate]
        Jv, gt = np.array(Jv_fn(q_now, t)), np.array(phi0_fn(q_now, t)).ravel()
        if Jv.size:
            rhs = -gt - Jv[:, by_rate] @ v_now[by_rate]
            v_now[others] = np.linalg.lstsq(Jv[:, others], rhs, rcond=None)[0]
            miss = np.abs(Jv @ v_now + gt)
            terms = np.abs(Jv) @ np.abs(v_now) + np.abs(gt)  # each row against the terms it adds up, above the
            solve = 1e3 * np.finfo(float).eps * np.abs(Jv).sum(axis=1) * np.abs(v_now).max(initial=0.0)  # round-off
            if np.any(miss > 1e-10 * terms + solve):
                worst = int(np.argmax(miss))
                raise InitialDataError(
                    f"Multibody.assemble: the rates {sorted(rate_keys)} contradict the joints — row "
                    f"{self._row_names()[worst]!r} moves at {miss[worst]:.3g}; hold fewer rates"
                )
        return q_now, v_now

    def _rate_aliases(self) -> dict[str, str]:
        """A coordinate's name for its velocity where the velocity is its rate: a planar body's three, a spatial
        body's centre (its quaternion has none: give ``ωx`` …)."""
        out: dict[str, str] = {}
        for b in self._bodies.values():
            out.update(zip(b.coordinate_names()[:3], b.velocity_names()[:3], strict=True))  # (x, y, θ) or (x, y, z)
        return out

    def _row_names(self, positions: bool = False) -> list[str]:
        """Every row's name in the constraints' order (``positions``: the position rows' only)."""
        return [str(c.name) for c in self.constraints if not positions or isinstance(c, Holonomic)]

    def _functions(self) -> tuple[ca.Function, ca.Function, ca.Function, ca.Function]:
        """``g(q, t)`` and ``∂g/∂q`` of the position rows; ``∂Φ/∂v`` and ``Φ(q, 0, t)`` of every row (``Φ`` affine in
        the velocities: a joint row's ``ġ``, a spin's ``(ω, e) − Ω``)."""
        mech = self.mechanism
        q, v, t = mech.q, mech.v, mech.t
        held = [c for c in self.constraints if isinstance(c, Holonomic)]
        g = ca.vertcat(*[ca.SX(c.value(q, t)) for c in held]) if held else ca.SX(0, 1)
        Phi = ca.vertcat(*[c.expressions(mech).Phi for c in self.constraints]) if self.constraints else ca.SX(0, 1)
        Jv = ca.jacobian(Phi, v)
        phi0 = ca.substitute(Phi, v, ca.SX.zeros(v.numel()))
        return tuple(  # type: ignore[return-value]
            ca.Function(n, [q, t], [x]) for n, x in (("g", g), ("G", ca.jacobian(g, q)), ("Jv", Jv), ("phi0", phi0))
        )

    # -- drawing ------------------------------------------------------------------------------------------
    def drawing(self, q: np.ndarray) -> dict[str, Any]:
        """The machine at ``q`` for :func:`gausspp.plot.animate`: each body as segments from its centre to its
        joints' points (a spatial machine seen along ``z``), the centres, the ground points."""
        q = np.asarray(q, float)
        segments, centres = [], []
        for b in self._bodies.values():
            r = np.array(ca.DM(b.parts(q)[0])).ravel()[:2]
            centres.append(r)
            for p in b.points:
                end = np.array(ca.DM(b.point(q, p))).ravel()[:2]
                segments.append((r, end))
        ground = [p[:2] for p in self._ground_points]
        out: dict[str, Any] = {"segments": segments, "points": centres}
        if ground:
            out["fixed"] = ground
        return out


def _twist(a: Body, b: Body | None, R0: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> J.Row:
    """The turn about a prismatic axis held: ``(R_a u₁)·(R_b R₀ᵀ u₂) = 0``."""
    target = ca.DM(R0.T @ u2)
    return lambda q, t: ca.dot(J.rotation(a, q, 3) @ ca.DM(u1), J.rotation(b, q, 3) @ target)


def _indices(
    values: Mapping[str, Any], names: list[str], what: str, aliases: Mapping[str, str] | None = None
) -> list[int]:
    out = []
    for key in values:
        name = (aliases or {}).get(key, key)
        if name not in names:
            raise UnknownNameError(f"Multibody.assemble: {what} names {key!r}, which is not one of {names}")
        out.append(names.index(name))
    return out
