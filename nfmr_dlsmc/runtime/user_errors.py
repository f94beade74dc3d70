"""
How a command or a node reports a user error: one line on stderr and exit status 2.

:func:`nfmr_dlsmc.cli.common.run_command` (every ``nfmr-*`` command) and
:func:`nfmr_dlsmc.ros.node_main.run_node` (both nodes) end a user error here, so that it
reads the same everywhere: ``<prog>: error: <message>``.
"""

import sys

from nfmr_dlsmc.core.errors import NfmrError

__all__ = ['report_user_error', 'USER_ERROR_STATUS']

#: The exit status of a user error (argparse's, for a bad command line).
USER_ERROR_STATUS = 2


def report_user_error(prog: str, error: NfmrError) -> int:
    """
    Print ``error`` as the one line ``<prog>: error: <message>`` on stderr.

    A message that spans lines is joined into one.

    Returns
    -------
    int
        :data:`USER_ERROR_STATUS`, the exit status to end with.

    """
    message = ' '.join(line.strip() for line in str(error).splitlines() if line.strip())
    print(f'{prog}: error: {message}', file=sys.stderr)
    return USER_ERROR_STATUS
