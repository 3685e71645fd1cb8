"""The LIGGGHTS 3.8.0 facts ligwf works around, in one place.

Contact angle (washino and easo, the Debian 3.8.0 release): the engine computes the
effective angle of a pair as ``0.5 * theta_i * theta_j`` (radians) instead of the mean
``0.5 * (theta_i + theta_j)`` (fixed upstream after the release). With 30 deg on both
partners it applies about 7.9 deg. For one particle type an input angle
``a = sqrt(2 theta)`` makes the engine apply ``theta``; ligwf writes that unless the scene
says the engine has the fix (``numerics.contact_angle_compensation: false``).

Restarts: SIGTERM makes the engine write ``restart_forced_liggghts_<step>.data`` in its
working folder; the drum input writes periodic restarts alternately to two files (so a
SIGKILL mid-write leaves the other one whole). The step is read from the binary header.

Library: ``libliggghts.so.3`` exports the LAMMPS C API (open, file, command, close), driven
through ctypes on an mpi4py sub-communicator by the ensemble worker.
"""

from __future__ import annotations

import ctypes
import math
import os
import re
import struct
from pathlib import Path

from ligwf.engine.site import load_site
from ligwf.liquids.base import InputAngle

#: what the input's comment says when ligwf compensates the contact-angle bug
CONTACT_ANGLE_NOTE = "LIGGGHTS 3.8.0 applies 0.5*a*a rad"


def engine_contact_angle_deg(theta_deg: float, compensate: bool = True) -> float:
    """Contact angle to write into the LIGGGHTS input so the engine applies ``theta_deg``.

    LIGGGHTS 3.8.0 applies ``0.5 * a * a`` (radians) for an input angle ``a`` on both
    partners. Solving ``0.5 a^2 = theta`` gives ``a = sqrt(2 theta)``, which stays within the
    engine's accepted [0, 180] deg for every theta in [0, 180] deg. With ``compensate=False``
    (an engine with the upstream fix) the angle is passed through.
    """
    if not compensate:
        return theta_deg
    return math.degrees(math.sqrt(2.0 * math.radians(theta_deg)))


def engine_effective_angle_rad(theta_in_deg_i: float, theta_in_deg_j: float | None = None,
                               product_bug: bool = True) -> float:
    """Effective angle (radians) the engine applies for input angles of two partners."""
    a = math.radians(theta_in_deg_i)
    b = math.radians(theta_in_deg_j if theta_in_deg_j is not None else theta_in_deg_i)
    return 0.5 * a * b if product_bug else 0.5 * (a + b)


def input_angle(theta_deg: float, compensate: bool) -> InputAngle:
    """The angle a liquid model writes for a scene angle ``theta_deg``, with its note."""
    return InputAngle(engine_contact_angle_deg(theta_deg, compensate),
                      CONTACT_ANGLE_NOTE if compensate else "")


def applied_contact_angle_rad(theta_deg: float, compensated: bool,
                              product_bug: bool = True) -> float:
    """The angle (rad) the engine applied in a run whose scene angle is ``theta_deg``:
    the scene's when ligwf compensated (or the engine has the fix), else 0.5 theta^2."""
    if compensated or not product_bug:
        return math.radians(theta_deg)
    return engine_effective_angle_rad(theta_deg, product_bug=True)


# --------------------------------------------------------------------------- restarts

#: the file a rank writes on SIGTERM, in the case folder (the engine's working folder)
FORCED_RESTART_RE = re.compile(r"^restart_forced_liggghts_(\d+)\.data$")
#: periodic restarts of the drum input, written alternately (templates/drum.in.j2)
PERIODIC_RESTARTS = ("restart/restart_a.liggghts", "restart/restart_b.liggghts")


def restart_step(path: Path) -> int | None:
    """Time step stored in a LIGGGHTS 3.8.0 restart file header, or None if unreadable.

    The header is a sequence of (int flag, value): 0 version string (int length + bytes),
    1-3 int sizes, 4 units string, 5 the time step as a 64-bit integer.
    """
    try:
        with open(path, "rb") as fh:
            data = fh.read(512)
        offset = 0
        flag, n = struct.unpack_from("<ii", data, offset)
        if flag != 0 or not 0 < n < 400:
            return None
        offset += 8 + n
        for expect in (1, 2, 3):
            flag, _ = struct.unpack_from("<ii", data, offset)
            if flag != expect:
                return None
            offset += 8
        flag, n = struct.unpack_from("<ii", data, offset)
        if flag != 4 or not 0 < n < 64:
            return None
        offset += 8 + n
        flag, step = struct.unpack_from("<iq", data, offset)
        if flag != 5 or step < 0:
            return None
        return int(step)
    except (OSError, struct.error):
        return None


# --------------------------------------------------------------------------- library

def library_path() -> str:
    """The LIGGGHTS shared library: $LIGWF_LIBLIGGGHTS, site key ``libliggghts``, or the
    Debian package's ``libliggghts.so.3`` (found by the dynamic loader)."""
    return os.environ.get("LIGWF_LIBLIGGGHTS", load_site().get("libliggghts", "libliggghts.so.3"))


class Liggghts:
    """The LAMMPS C API of libliggghts through ctypes (open, file, close)."""

    def __init__(self, path: str | None = None) -> None:
        self.lib = ctypes.CDLL(path or library_path(), mode=ctypes.RTLD_GLOBAL)
        self.lib.lammps_open.argtypes = [ctypes.c_int, ctypes.POINTER(ctypes.c_char_p),
                                         ctypes.c_void_p, ctypes.POINTER(ctypes.c_void_p)]
        self.lib.lammps_open.restype = None
        self.lib.lammps_file.argtypes = [ctypes.c_void_p, ctypes.c_char_p]
        self.lib.lammps_file.restype = None
        self.lib.lammps_close.argtypes = [ctypes.c_void_p]
        self.lib.lammps_close.restype = None
        self.lib.lammps_command.argtypes = [ctypes.c_void_p, ctypes.c_char_p]
        self.lib.lammps_command.restype = ctypes.c_char_p

    def warm_up_vtk(self) -> None:
        """Create (never write) one VTK dump in a throw-away engine on MPI_COMM_SELF.

        The first ``dump custom/vtk`` of a process runs vtkMPIController::Initialize,
        which calls MPI_Comm_dup on MPI_COMM_WORLD -- a collective over ALL ranks of the
        job (seen in gdb). If group A reaches its first dump while group B is still
        filling, or has failed, A waits forever. Doing it on every rank at start-up, all
        at once, makes later dumps local (VTK initialises only once per process).
        """
        from mpi4py import MPI

        args = [b"liggghts", b"-screen", b"none", b"-log", b"none"]
        argv = (ctypes.c_char_p * len(args))(*args)
        handle = ctypes.c_void_p()
        comm_ptr = ctypes.c_void_p.from_address(MPI._addressof(MPI.COMM_SELF))
        self.lib.lammps_open(len(args), argv, comm_ptr, ctypes.byref(handle))
        for cmd in ("units si", "atom_style granular", "region box block 0 1 0 1 0 1 units box",
                    "create_box 1 box", "dump warm all custom/vtk 1000000 warm_*.vtu id"):
            self.lib.lammps_command(handle, cmd.encode())
        self.lib.lammps_close(handle)
