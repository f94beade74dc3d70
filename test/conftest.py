"""
Shared test set-up: this session's DDS traffic kept to itself, and an open-loop controller.

DDS: loopback only, a domain of its own, held for the whole session as ``nfmr-run`` holds its
own (so that a run of another session never takes it), and the run's discovery profile.
"""

import os
import signal

from nfmr_dlsmc.runtime.ros_domain import FASTDDS_PROFILE, reserve_domain
from nfmr_dlsmc.runtime.share import shipped_config
import pytest
from ros_helpers import release_participants

# A shell starting the suite in the background without job control has it ignore SIGINT,
# and every command it starts would inherit that: the tests that stop a command with
# SIGINT need the default, Python's KeyboardInterrupt.
signal.signal(signal.SIGINT, signal.default_int_handler)

os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
if 'ROS_DOMAIN_ID' not in os.environ:
    SESSION_DOMAIN = reserve_domain()  # released when the session's process ends
    os.environ['ROS_DOMAIN_ID'] = str(SESSION_DOMAIN.domain)
# Fast DDS announcing as often as in a run: nodes the tests start are found in tenths of a
# second, not at the 3 s announcement of the defaults (doc/design.md, D13).
os.environ.setdefault(FASTDDS_PROFILE[0], str(shipped_config(FASTDDS_PROFILE[1])))


@pytest.fixture(autouse=True)
def _participants_released():
    """After each test, free the DDS participants of its contexts (see release_participants)."""
    yield
    release_participants()


class _ConstantInputs:
    """A controller that always commands the same (v [m/s], omega [rad/s]): isolates the plant."""

    TELEMETRY_FIELDS = ('theta_d', 'omega_saturated')

    def __init__(self, v, omega):
        self.v, self.omega = v, omega

    def reset(self):
        """Do nothing: the controller has no state."""

    def step(self, *_):
        """Return the constant (v, omega)."""
        return self.v, self.omega

    def telemetry(self):
        """Return a theta_d of 0 and no saturation."""
        return (0.0, 0.0)


@pytest.fixture
def constant_inputs():
    """Return the open-loop controller class; an instance is made from (v, omega)."""
    return _ConstantInputs
