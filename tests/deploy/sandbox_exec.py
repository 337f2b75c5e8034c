"""Run a command under the kernel restrictions that gauged.service asks systemd for.

    python sandbox_exec.py [--mdwe] [--syscalls FILE] [--families AF_UNIX,AF_INET,...] -- CMD ARGS...

Without systemd as PID 1 (containers, CI) the unit's sandbox cannot be started as a service, but
three of its settings are plain kernel features that this launcher applies itself before it
``execve``\\ s the command, which inherits them:

- ``MemoryDenyWriteExecute=yes``: ``prctl(PR_SET_MDWE, PR_MDWE_REFUSE_EXEC_GAIN)`` (Linux 6.3+),
  the kernel's own form of the same rule (systemd 256+ uses it too);
- ``SystemCallFilter=`` with ``SystemCallErrorNumber=EPERM``: a seccomp filter through libseccomp
  that allows the syscalls listed in FILE (one name per line) and fails every other one with EPERM;
- ``RestrictAddressFamilies=``: ``socket()`` is allowed only for the listed families (systemd
  answers EAFNOSUPPORT to the others, this filter EPERM).

Exit 77 when the kernel or libseccomp lacks what was asked for.
"""

from __future__ import annotations

import argparse
import ctypes
import ctypes.util
import errno
import os
import socket
import sys

PR_SET_MDWE, PR_MDWE_REFUSE_EXEC_GAIN = 65, 1
SCMP_ACT_ALLOW = 0x7FFF0000
SCMP_CMP_EQ = 4
EXIT_UNSUPPORTED = 77


def scmp_act_errno(code: int) -> int:
    return 0x00050000 | (code & 0x0000FFFF)


class ScmpArgCmp(ctypes.Structure):
    _fields_ = [("arg", ctypes.c_uint), ("op", ctypes.c_int), ("datum_a", ctypes.c_uint64),
                ("datum_b", ctypes.c_uint64)]


def unsupported(message: str) -> None:
    print(f"sandbox_exec: {message}", file=sys.stderr)
    sys.exit(EXIT_UNSUPPORTED)


def deny_write_execute() -> None:
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_MDWE, PR_MDWE_REFUSE_EXEC_GAIN, 0, 0, 0) != 0:
        unsupported(f"PR_SET_MDWE failed (errno {ctypes.get_errno()}): needs Linux 6.3+")


def load_syscall_filter(allowed: list[str], families: list[str]) -> None:
    name = ctypes.util.find_library("seccomp")
    if name is None:
        unsupported("libseccomp not found (Debian package libseccomp2)")
    lib = ctypes.CDLL(name)
    lib.seccomp_init.restype = ctypes.c_void_p
    lib.seccomp_init.argtypes = [ctypes.c_uint32]
    lib.seccomp_syscall_resolve_name.argtypes = [ctypes.c_char_p]
    lib.seccomp_rule_add_array.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.c_int, ctypes.c_uint,
                                           ctypes.POINTER(ScmpArgCmp)]
    lib.seccomp_load.argtypes = [ctypes.c_void_p]
    ctx = lib.seccomp_init(scmp_act_errno(errno.EPERM))
    if not ctx:
        unsupported("seccomp_init failed")
    for syscall in allowed:
        nr = lib.seccomp_syscall_resolve_name(syscall.encode())
        if nr < 0:  # a name of another architecture (e.g. fstatat64 on x86_64)
            continue
        if syscall == "socket" and families:
            for family in families:
                cmp = ScmpArgCmp(0, SCMP_CMP_EQ, int(getattr(socket, family)), 0)
                rc = lib.seccomp_rule_add_array(ctx, SCMP_ACT_ALLOW, nr, 1, ctypes.byref(cmp))
                if rc != 0:
                    unsupported(f"seccomp_rule_add socket({family}) failed: {rc}")
            continue
        rc = lib.seccomp_rule_add_array(ctx, SCMP_ACT_ALLOW, nr, 0, None)
        if rc != 0:
            unsupported(f"seccomp_rule_add {syscall} failed: {rc}")
    rc = lib.seccomp_load(ctx)  # also sets no_new_privs, as NoNewPrivileges=yes does
    if rc != 0:
        unsupported(f"seccomp_load failed: {rc}")


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--mdwe", action="store_true")
    parser.add_argument("--syscalls", metavar="FILE")
    parser.add_argument("--families", default="")
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no command")
    if args.mdwe:
        deny_write_execute()
    if args.syscalls:
        with open(args.syscalls) as listing:
            allowed = [line.strip() for line in listing if line.strip()]
        load_syscall_filter(allowed, [f for f in args.families.split(",") if f])
    os.execv(command[0], command)


if __name__ == "__main__":
    main(sys.argv[1:])
