"""
The root of the errors nfmr reports to its user.

Every command and both nodes catch :class:`NfmrError` in one place
(:func:`nfmr_dlsmc.cli.common.run_command`, :func:`nfmr_dlsmc.ros.node_main.run_node`) and
print its message as one line, ``<prog>: error: <message>``: a parameter, a parameter file,
a path, a bag or a command line the user gave is wrong, and the message says which and how.
That is exit status 2, but for a run that started and could not complete
(:class:`~nfmr_dlsmc.ros.node_processes.RunError`: a child died, the run stalled, another source
reached it), which ``nfmr-run`` reports as exit status 1 after finishing its bag. Anything
else is a bug and keeps its traceback.

Below it: :class:`~nfmr_dlsmc.core.validation.ParameterError` (and its
:class:`~nfmr_dlsmc.core.path_reference.PathError`),
:class:`~nfmr_dlsmc.runtime.params.ParamsFileError`,
:class:`~nfmr_dlsmc.runtime.path_files.PathFileError`,
:class:`~nfmr_dlsmc.bag.reader.BagError`, :class:`~nfmr_dlsmc.cli.common.UsageError`,
:class:`~nfmr_dlsmc.ros.node_main.RosArgumentsError`,
:class:`~nfmr_dlsmc.analysis.animation.AnimationError`,
:class:`~nfmr_dlsmc.analysis.chassis_tuning.StudyError`,
:class:`~nfmr_dlsmc.runtime.worker_pool.ClusterError` and
:class:`~nfmr_dlsmc.ros.node_processes.RunError`.
"""

__all__ = ['NfmrError']


class NfmrError(Exception):
    """A user error: the message, one line, says what is wrong and what is allowed."""
