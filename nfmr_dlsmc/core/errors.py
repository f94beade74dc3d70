"""
The root of the errors nfmr reports to its user.

Every command and both nodes catch :class:`NfmrError` in one place
(:func:`nfmr_dlsmc.cli.common.run_command`, :func:`nfmr_dlsmc.ros.node_main.run_node`) and
print its message as one line, exit status 2: a parameter, a parameter file, a bag or a run
the user asked for is wrong, and the message says which and how. Anything else is a bug and
keeps its traceback.

Below it: :class:`~nfmr_dlsmc.core.validation.ParameterError`,
:class:`~nfmr_dlsmc.runtime.params.ParamsFileError`,
:class:`~nfmr_dlsmc.bag.reader.BagError` and :class:`~nfmr_dlsmc.ros.launcher.RunError`.
"""

__all__ = ['NfmrError']


class NfmrError(Exception):
    """A user error: the message, one line, says what is wrong and what is allowed."""
