"""The fence around a process that runs user code (a `sim run` child, a virtual hub).

User code never runs in the daemon or CLI process. The process that does run it fences itself in
with what the operating system enforces, whatever the code manages to reach inside Python:

- RLIMIT_AS caps its address space, so a runaway allocation ends in the program's MemoryError
  instead of the machine swapping;
- RLIMIT_CPU caps its processor time: at the soft limit the kernel sends SIGXCPU (turned into
  CpuLimitExceeded in the program), one second later SIGKILL, which no program can catch;
- RLIMIT_FSIZE caps the size of any file it writes (SIGXFSZ is ignored, so the write fails with
  EFBIG instead of killing the process);
- RLIMIT_NPROC leaves room for a few more threads of this user, not a fork bomb (the kernel does
  not apply it to root);
- PR_SET_NO_NEW_PRIVS: nothing it executes can gain privileges (setuid binaries, file caps);
- a seccomp filter refuses the system calls that make a new process or run a program (fork,
  vfork, clone without CLONE_THREAD, execve, execveat; clone3 answers ENOSYS so the C library
  falls back to clone, where the flags can be checked), and refuses to change a resource limit
  (setrlimit, prlimit64 with a new limit: reading one still works). Threads still start. This
  holds for root too, which is what makes "no new processes" and "limits for good" true in a
  container running as root.

The in-process layers (the hub's own builtins, imports limited to the ESP32 port's modules, file
access only on the hub's flash) keep honest programs on the hub's API; they are not a security
boundary by themselves, since Python code can always reach the interpreter's internals. This
module is the layer that holds when they are bypassed.
"""

import ctypes
import errno
import os
import resource
import signal
import struct

DEFAULT_MEMORY_MB = 1024
DEFAULT_FILE_MB = 64  # a hub's flash is a few MB; the host's disk is not the program's
MIN_WALL_S = 10.0  # the shortest default wall-clock limit: start-up alone takes a second or two
CPU_MARGIN_S = 5  # the default CPU limit is the wall limit plus this (one busy core at most)
THREAD_HEADROOM = 64  # RLIMIT_NPROC: tasks this user may still start (threads), for non-root users

PR_SET_NO_NEW_PRIVS = 38
PR_SET_SECCOMP = 22
SECCOMP_MODE_FILTER = 2
CLONE_THREAD = 0x00010000


# What contain() set in this process, for the messages that name a limit: {"cpu_s": ..., ...}
applied = {}


class CpuLimitExceeded(BaseException):
    """The process used its processor time (RLIMIT_CPU): a BaseException, so `except Exception` in
    the program cannot keep it running."""


def default_wall_s(limit_ms, speed=None):
    """The wall-clock limit that goes with a simulated-time limit: a paced run needs its simulated
    time over the speed, twice over; an unpaced one runs many times faster than real time, so its
    simulated time as wall time is a wide margin. Never under MIN_WALL_S."""
    sim_s = (limit_ms or 0) / 1000.0
    wall_s = 2.0 * sim_s / speed if speed else sim_s
    return max(MIN_WALL_S, wall_s)


def default_cpu_s(wall_s):
    """The CPU-time limit that goes with a wall-clock limit (a run keeps one core busy at most)."""
    return int(wall_s) + CPU_MARGIN_S if wall_s else None


def contain(memory_mb=DEFAULT_MEMORY_MB, cpu_s=None, file_mb=DEFAULT_FILE_MB):
    """Fence this process in for good (limits can only be lowered again): memory, CPU time, file
    size, processes and privileges. 0 or None leaves that resource as it is."""
    applied.update(memory_mb=memory_mb or None, cpu_s=cpu_s or None, file_mb=file_mb or None)
    if memory_mb:
        _lower(resource.RLIMIT_AS, memory_mb * 1024 * 1024)
    if cpu_s:
        signal.signal(signal.SIGXCPU, _cpu_limit_reached)
        used_s = int(sum(os.times()[:2]))
        _lower(resource.RLIMIT_CPU, used_s + int(cpu_s), used_s + int(cpu_s) + 1)
    if file_mb:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        _lower(resource.RLIMIT_FSIZE, file_mb * 1024 * 1024)
    if os.getuid() != 0:
        _lower(resource.RLIMIT_NPROC, _tasks_of_this_user() + THREAD_HEADROOM)
    no_new_privileges()
    forbid_new_processes()


def _lower(which, soft, hard=None):
    """Set a limit for good: the hard limit too (`hard`, else the soft one), so code that reaches
    setrlimit() cannot raise it again; never above what the limit already is."""
    hard = soft if hard is None else hard
    old_soft, old_hard = resource.getrlimit(which)
    if old_hard != resource.RLIM_INFINITY:
        hard = min(hard, old_hard)
    if old_soft != resource.RLIM_INFINITY:
        soft = min(soft, old_soft)
    resource.setrlimit(which, (min(soft, hard), hard))


def _cpu_limit_reached(_signum, _frame):
    signal.signal(signal.SIGXCPU, signal.SIG_IGN)  # once: the hard limit's SIGKILL follows anyway
    raise CpuLimitExceeded()


def _tasks_of_this_user():
    """How many tasks (processes and their threads) this user runs now: what RLIMIT_NPROC counts."""
    uid = str(os.getuid())
    count = 0
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open(f"/proc/{pid}/status", encoding="ascii", errors="replace") as status:
                fields = dict(line.split(":", 1) for line in status if ":" in line)
        except OSError:
            continue
        if fields.get("Uid", "").split()[:1] == [uid]:
            count += int(fields.get("Threads", "1").strip() or 1)
    return count


def _prctl(option, arg2, arg3=0, arg4=0, arg5=0):
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl.argtypes = [ctypes.c_int, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong]
    if libc.prctl(option, arg2, arg3, arg4, arg5) != 0:
        code = ctypes.get_errno()
        raise OSError(code, f"prctl({option}): {os.strerror(code)}")


def no_new_privileges():
    """PR_SET_NO_NEW_PRIVS: execve can no longer grant privileges (setuid, file capabilities)."""
    _prctl(PR_SET_NO_NEW_PRIVS, 1)


# -- seccomp: no new processes, no programs run ---------------------------------------------------

# (audit arch, syscalls refused with EPERM, clone, clone3, prlimit64, lowest number of a foreign ABI)
_SYSCALLS = {
    # fork vfork execve execveat setrlimit; x32 numbers from 0x40000000 up
    "x86_64": (0xC000003E, (57, 58, 59, 322, 160), 56, 435, 302, 0x40000000),
    # execve execveat setrlimit (no fork/vfork calls)
    "aarch64": (0xC00000B7, (221, 281, 164), 220, 435, 261, None),
}

_LD_W_ABS = 0x20
_JEQ_K = 0x15
_JGE_K = 0x35
_JSET_K = 0x45
_RET_K = 0x06
_RET_ALLOW = 0x7FFF0000
_RET_ERRNO = 0x00050000
# struct seccomp_data: nr, arch, then 64-bit args from offset 16 (little-endian: low word first)
_NR_OFFSET, _ARCH_OFFSET, _ARG0_OFFSET, _ARG2_OFFSET = 0, 4, 16, 32


def _filter_program(arch, refused, clone, clone3, prlimit, foreign_abi):
    """The BPF program as (code, jump-if-true label, jump-if-false label, k) with labels resolved."""
    program = [
        (_LD_W_ABS, None, None, _ARCH_OFFSET),
        (_JEQ_K, None, "deny", arch),
        (_LD_W_ABS, None, None, _NR_OFFSET),
    ]
    if foreign_abi is not None:
        program.append((_JGE_K, "deny", None, foreign_abi))
    program += [(_JEQ_K, "deny", None, nr) for nr in refused]
    program += [
        (_JEQ_K, "clone", None, clone),
        (_JEQ_K, "enosys", None, clone3),
        (_JEQ_K, "prlimit", None, prlimit),
        (_RET_K, None, None, _RET_ALLOW),
        ("clone", _LD_W_ABS, None, None, _ARG0_OFFSET),
        (_JSET_K, "allow", "deny", CLONE_THREAD),  # a thread (BPF jumps only forward)
        ("prlimit", _LD_W_ABS, None, None, _ARG2_OFFSET),  # the new limit: NULL reads only
        (_JEQ_K, None, "deny", 0),
        (_LD_W_ABS, None, None, _ARG2_OFFSET + 4),
        (_JEQ_K, "allow", "deny", 0),
        ("allow", _RET_K, None, None, _RET_ALLOW),
        ("deny", _RET_K, None, None, _RET_ERRNO | errno.EPERM),
        ("enosys", _RET_K, None, None, _RET_ERRNO | errno.ENOSYS),
    ]
    labels, plain = {}, []
    for entry in program:
        if isinstance(entry[0], str):
            labels[entry[0]] = len(plain)
            entry = entry[1:]
        plain.append(entry)
    resolved = []
    for index, (code, true, false, k) in enumerate(plain):
        jt = 0 if true is None else labels[true] - index - 1
        jf = 0 if false is None else labels[false] - index - 1
        resolved.append((code, jt, jf, k))
    return resolved


def forbid_new_processes():
    """Install the seccomp filter: fork, vfork, clone of a process, execve and execveat fail with
    EPERM from now on, in this process and its threads. Needs no_new_privileges() first (or root).
    On a machine whose architecture has no table here, nothing is installed."""
    table = _SYSCALLS.get(os.uname().machine)
    if table is None:
        return False
    instructions = _filter_program(*table)
    raw = b"".join(struct.pack("<HBBI", *instruction) for instruction in instructions)
    buffer = ctypes.create_string_buffer(raw, len(raw))

    class SockFprog(ctypes.Structure):
        _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]

    prog = SockFprog(len(instructions), ctypes.addressof(buffer))
    _prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, ctypes.addressof(prog))
    return True
