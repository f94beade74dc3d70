"""A child process that ends when its parent does, even when the parent was SIGKILLed."""

import ctypes
import signal

__all__ = ['die_with_parent']

#: prctl's option that sends the caller a signal when its parent thread ends (Linux).
_PR_SET_PDEATHSIG = 1


def die_with_parent(signum: int = signal.SIGTERM) -> None:
    """
    In a child: have the kernel send it ``signum`` when its parent dies (Linux; no-op else).

    For ``preexec_fn`` of a subprocess or the initializer of a process pool: a parent killed
    by SIGKILL or a timeout runs no cleanup, and its children would go on computing.
    """
    try:
        ctypes.CDLL('libc.so.6', use_errno=True).prctl(_PR_SET_PDEATHSIG, signum)
    except OSError:
        pass
