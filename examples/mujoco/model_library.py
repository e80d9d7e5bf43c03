"""A toolconf model library (`make model`) through its C ABI, with ctypes.

The library is the one a C or C++ controller links (docs/reference/c-abi.md, `toolconf_model.h` beside
it): its metadata, the plant and the rigid-body dynamics, the tool tip's forward kinematics and
the on-robot controller (create, tick, destroy). Arrays are flat doubles, matrices column-major,
as the header says; every call's status is checked and a failure raised as `LibraryError` with
the library's own message.
"""

from __future__ import annotations

import ctypes
from ctypes import POINTER, c_char_p, c_double, c_int32, c_size_t, c_uint32, c_void_p
from pathlib import Path

import numpy as np

# The C ABI this binding speaks (toolconf_model.h's TOOLCONF_ABI_VERSION): version 2 made controller
# handles registry keys and added TOOLCONF_OUT_OF_MEMORY, with every signature and struct unchanged.
ABI_VERSION = 2
_DOUBLES = POINTER(c_double)


class LibraryError(RuntimeError):
    """A nonzero status from the library: its name and the library's message."""


class _Domain(ctypes.Structure):
    _fields_ = [("lo", c_double), ("hi", c_double), ("lo_open", c_int32),
                ("hi_open", c_int32), ("rule", c_char_p)]


class _Constraint(ctypes.Structure):
    _fields_ = [("coefficients", _DOUBLES), ("rule", c_char_p)]


class _InertiaRule(ctypes.Structure):
    _fields_ = [("moments", c_uint32 * 3), ("products", c_uint32 * 3), ("slack", c_double),
                ("rule", c_char_p)]


class _Metadata(ctypes.Structure):
    """toolconf_metadata, field for field (toolconf_model.h)."""
    _fields_ = [
        ("abi_version", c_uint32), ("name", c_char_p), ("title", c_char_p),
        ("description", c_char_p), ("dof", c_size_t), ("state_dim", c_size_t),
        ("parameter_count", c_size_t), ("tip_dim", c_size_t), ("has_tip", c_int32),
        ("parameter_names", POINTER(c_char_p)), ("parameter_units", POINTER(c_char_p)),
        ("state_names", POINTER(c_char_p)), ("control_names", POINTER(c_char_p)),
        ("domains", POINTER(_Domain)), ("constraint_count", c_size_t),
        ("constraints", POINTER(_Constraint)), ("sample_lo", _DOUBLES), ("sample_hi", _DOUBLES),
        ("has_default", POINTER(c_int32)), ("defaults", _DOUBLES), ("has_inertia", c_int32),
        ("inertia", _InertiaRule), ("equilibrium_state", _DOUBLES),
        ("equilibrium_control", _DOUBLES), ("task_count", c_size_t),
        ("task_names", POINTER(c_char_p)), ("task_offered", POINTER(c_int32)),
        ("term_count", c_size_t), ("term_names", POINTER(c_char_p)),
        ("tasks_fingerprint", c_char_p),
    ]


def _declare(lib: ctypes.CDLL) -> None:
    """The signatures of the exports this module calls."""
    p, vp = _DOUBLES, c_void_p
    signatures = {
        "toolconf_abi_version": (c_uint32, []),
        "toolconf_model_info": (POINTER(_Metadata), []),
        "toolconf_last_error": (c_char_p, []),
        "toolconf_status_name": (c_char_p, [c_int32]),
        "toolconf_check_tool": (c_int32, [p]),
        "toolconf_dynamics": (c_int32, [p, p, p, p]),
        "toolconf_rigid_body_dynamics": (c_int32, [p, p, p, p]),
        "toolconf_tip": (c_int32, [p, p, p, p]),
        "toolconf_state_matrix": (c_int32, [p, p]),
        "toolconf_controller_create": (c_int32, [p, c_uint32, p, p, c_double, p, c_double,
                                                 POINTER(vp)]),
        "toolconf_controller_destroy": (c_int32, [vp]),
        "toolconf_controller_tick": (c_int32, [vp, p, p, p]),
        "toolconf_controller_pi_u": (c_int32, [vp, p]),
    }
    for name, (restype, argtypes) in signatures.items():
        function = getattr(lib, name)
        function.restype, function.argtypes = restype, argtypes


def _pointer(array: np.ndarray):
    return array.ctypes.data_as(_DOUBLES)


def _vector(values, size: int, what: str) -> np.ndarray:
    array = np.ascontiguousarray(values, dtype=np.float64).reshape(-1)
    if array.size != size:
        raise ValueError(f"{what}: {array.size} values, the model takes {size}")
    return array


class ModelLibrary:
    """One model library, loaded from the folder `make model` wrote (or the .so itself)."""

    def __init__(self, path: str | Path):
        path = Path(path)
        if path.is_dir():
            found = sorted(path.glob("libtoolconf_model_*.so"))
            if len(found) != 1:
                raise LibraryError(f"{path}: no single libtoolconf_model_<model>.so in it")
            path = found[0]
        self.path = path
        self._lib = ctypes.CDLL(str(path))
        _declare(self._lib)
        version = self._lib.toolconf_abi_version()
        if version != ABI_VERSION:
            raise LibraryError(f"{path}: C ABI version {version}, this binding's {ABI_VERSION}")
        info = self._lib.toolconf_model_info()
        if not info:
            raise LibraryError(f"{path}: toolconf_model_info: {self._message()}")
        m = info.contents
        self.name = m.name.decode()
        self.dof, self.state_dim, self.parameter_count = m.dof, m.state_dim, m.parameter_count
        self.tip_dim = m.tip_dim if m.has_tip else 0
        self.parameter_names = [m.parameter_names[i].decode() for i in range(m.parameter_count)]
        self.task_names = [m.task_names[i].decode() for i in range(m.task_count)]
        self.term_names = [m.term_names[i].decode() for i in range(m.term_count)]
        self.equilibrium_state = np.array([m.equilibrium_state[i] for i in range(m.state_dim)])

    def _message(self) -> str:
        return (self._lib.toolconf_last_error() or b"").decode(errors="replace")

    def _check(self, status: int, what: str) -> None:
        if status != 0:
            name = self._lib.toolconf_status_name(status).decode()
            raise LibraryError(f"{what}: {name}: {self._message()}")

    def params(self, values) -> np.ndarray:
        """The tool's parameters as the library takes them, checked by the model's tool rule."""
        p = _vector(values, self.parameter_count, "tool parameters")
        self._check(self._lib.toolconf_check_tool(_pointer(p)), "toolconf_check_tool")
        return p

    def dynamics(self, x, u, p) -> np.ndarray:
        """Ẋ = f(X, U; p): the plant (for a URDF arm: the arm under joint impedance)."""
        return self._state_rate("toolconf_dynamics", x, u, p)

    def rigid_body_dynamics(self, x, u, p) -> np.ndarray:
        """Ẋ of the rigid-body dynamics alone, U the joint torques."""
        return self._state_rate("toolconf_rigid_body_dynamics", x, u, p)

    def _state_rate(self, export: str, x, u, p) -> np.ndarray:
        x = _vector(x, self.state_dim, "state")
        u = _vector(u, self.dof, "control")
        p = _vector(p, self.parameter_count, "tool parameters")
        out = np.empty(self.state_dim)
        status = getattr(self._lib, export)(_pointer(x), _pointer(u), _pointer(p), _pointer(out))
        self._check(status, export)
        return out

    def tip(self, q, p) -> tuple[np.ndarray, np.ndarray]:
        """The tool tip y(q) in the base frame (3) and its Jacobian ∂y/∂q (3 × dof)."""
        q = _vector(q, self.dof, "joint positions")
        p = _vector(p, self.parameter_count, "tool parameters")
        y, jacobian = np.empty(3), np.empty(3 * self.dof)
        self._check(self._lib.toolconf_tip(_pointer(q), _pointer(p), _pointer(y),
                                           _pointer(jacobian)), "toolconf_tip")
        return y, jacobian.reshape((3, self.dof), order="F")

    def state_matrix(self, p) -> np.ndarray:
        """A = ∂f/∂X of the plant at the equilibrium (state_dim × state_dim)."""
        p = _vector(p, self.parameter_count, "tool parameters")
        a = np.empty(self.state_dim * self.state_dim)
        self._check(self._lib.toolconf_state_matrix(_pointer(p), _pointer(a)),
                    "toolconf_state_matrix")
        return a.reshape((self.state_dim, self.state_dim), order="F")

    def controller(self, p, task: str, goals: np.ndarray, precisions: np.ndarray,
                   learning_rate: float, initial_torque, rate_hz: float) -> "Controller":
        """The on-robot controller of tool `p` for `task` (a name of `task_names`): goals
        (terms × dof) and precisions (terms × dof × dof), padded as the header says."""
        if task not in self.task_names:
            raise ValueError(f"task {task!r}: the model's tasks are {', '.join(self.task_names)}")
        n, t = self.dof, len(self.term_names)
        goals = _vector(np.asarray(goals).reshape(-1), t * n, "goals")
        # Column-major blocks: each term's matrix stored transposed in C order.
        blocks = np.asarray(precisions, dtype=np.float64).reshape(t, n, n)
        flat = np.ascontiguousarray(blocks.transpose(0, 2, 1)).reshape(-1)
        u0 = _vector(initial_torque, n, "initial torque")
        p = _vector(p, self.parameter_count, "tool parameters")
        handle = c_void_p()
        status = self._lib.toolconf_controller_create(
            _pointer(p), self.task_names.index(task), _pointer(goals), _pointer(flat),
            learning_rate, _pointer(u0), rate_hz, ctypes.byref(handle))
        self._check(status, "toolconf_controller_create")
        return Controller(self, handle)


class Controller:
    """A live controller: `tick(state)` once per period; `close()` (or `with`) frees it."""

    def __init__(self, library: ModelLibrary, handle: c_void_p):
        self._library, self._handle = library, handle
        n = library.dof
        self._state = np.empty(library.state_dim)
        self.torque = np.empty(n)
        self._confidence = c_double()
        self._tick = library._lib.toolconf_controller_tick
        self._pointers = (_pointer(self._state), _pointer(self.torque),
                          ctypes.byref(self._confidence))

    def tick(self, q: np.ndarray, q_dot: np.ndarray) -> np.ndarray:
        """One period: the measured X = [q; q̇] in, the torque for the next period out (a view
        the next tick overwrites)."""
        n = self._library.dof
        self._state[:n], self._state[n:] = q, q_dot
        status = self._tick(self._handle, *self._pointers)
        if status != 0:
            self._library._check(status, "toolconf_controller_tick")
        return self.torque

    @property
    def confidence(self) -> float:
        """ln|Π^U| as the last tick returned it."""
        return self._confidence.value

    def pi_u(self) -> np.ndarray:
        n = self._library.dof
        out = np.empty(n * n)
        self._library._check(self._library._lib.toolconf_controller_pi_u(self._handle,
                                                                         _pointer(out)),
                             "toolconf_controller_pi_u")
        return out.reshape((n, n), order="F")

    def close(self) -> None:
        if self._handle:
            self._library._lib.toolconf_controller_destroy(self._handle)
            self._handle = c_void_p()

    def __enter__(self) -> "Controller":
        return self

    def __exit__(self, *_exc) -> None:
        self.close()
