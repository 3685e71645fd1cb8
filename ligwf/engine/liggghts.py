"""The LIGGGHTS 3.8.0 facts ligwf works around, in one place.

Contact angle: the 3.8.0 law of the capillary models (0.5 theta_i theta_j) and ligwf's
compensation are :mod:`ligwf.liquids.contact_angle` (every layer that evaluates a bridge
needs them).

Restarts: SIGTERM makes the engine write ``restart_forced_liggghts_<step>.data`` in its
working folder; the drum input writes periodic restarts alternately to two files (so a
SIGKILL mid-write leaves the other one whole). The step is read from the binary header.

Library: ``libliggghts.so.3`` exports the LAMMPS C API (open, file, command, close), driven
through ctypes on an mpi4py sub-communicator by the ensemble worker. Which library file is
not a setting of its own: it is the one the named executable links to
(:meth:`ligwf.engine.site.EngineConfig.identify`).
"""

from __future__ import annotations

import ctypes
import struct
from pathlib import Path

from ligwf.engine.site import EngineConfig

# --------------------------------------------------------------------------- restarts



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
    """The LIGGGHTS shared library of the site's engine: the file the configured ``liggghts``
    executable links to (EngineNotFound when there is none)."""
    return EngineConfig.from_site().identify().library


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

    @staticmethod
    def mapped() -> set[str]:
        """The libliggghts files mapped into this process (``/proc/self/maps``): what the
        ensemble worker checks against the library it was told to load."""
        try:
            lines = Path("/proc/self/maps").read_text().splitlines()
        except OSError:
            return set()
        paths = {line.split(None, 5)[5] for line in lines if len(line.split(None, 5)) == 6}
        return {p for p in paths if Path(p).name.startswith("libliggghts")}

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
