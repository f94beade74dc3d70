"""
A ROS domain of its own for one run, so that no other ROS traffic reaches it (no rclpy).

A run's nodes talk on a domain no other participant on this host uses, with discovery kept
to this host (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``): two runs, or a run and someone
else's nodes, never see each other's topics (doc/design.md, D13). A domain is taken when
the first participant's discovery port of the RTPS port mapping (7400 + 250 d + 10) is
bound; the reservation holds that port for the whole run, so that a second run started at
the same moment picks another domain, and the run's own participants take the next ones.
"""

import os
import random
import socket

from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.share import shipped_config

__all__ = ['DOMAINS', 'DomainReservation', 'FASTDDS_PROFILE', 'discovery_port',
           'reserve_domain']

#: The Fast DDS profile of a run's processes (participants announcing every 0.25 s: a node
#: started beside running ones is found within tenths of a second, not 3 s; writers with a
#: NACK-suppression window: a publish no longer wakes Fast DDS's event thread) and the
#: variable that names it; a profile the user names in that variable is kept.
FASTDDS_PROFILE = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'fastdds_profile.xml')

#: Domains a run may take: 1-101 (0 is everyone's default; above 101 the ports of many
#: participants would reach the ephemeral range on Linux, as ROS 2's documentation warns).
DOMAINS = range(1, 102)


def discovery_port(domain: int) -> int:
    """Return the RTPS metatraffic unicast port of participant 0 on ``domain``."""
    return 7400 + 250 * domain + 10


class DomainReservation:
    """A domain held by a bound discovery port; :meth:`release` frees it (idempotent)."""

    def __init__(self, domain: int, sock: socket.socket | None):
        self.domain = domain
        self._socket = sock

    def environment(self) -> dict:
        """
        Return the variables that put a process on this domain, discovering this host only.

        With the run's Fast DDS profile (:data:`FASTDDS_PROFILE`) unless the environment
        names one already.
        """
        variable, profile = FASTDDS_PROFILE
        return {'ROS_DOMAIN_ID': str(self.domain),
                'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST',
                variable: os.environ.get(variable) or str(shipped_config(profile))}

    def release(self) -> None:
        if self._socket is not None:
            self._socket.close()
            self._socket = None


def _bind(domain: int) -> socket.socket | None:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.bind(('0.0.0.0', discovery_port(domain)))
    except OSError:
        sock.close()
        return None
    return sock


def reserve_domain(requested: int | None = None, rng: random.Random | None = None):
    """
    Reserve ``requested``, or a free domain of :data:`DOMAINS` chosen at random.

    Raises
    ------
    ParameterError
        ``requested`` is not within 0-232, or no domain of :data:`DOMAINS` is free.

    """
    if requested is not None:
        if isinstance(requested, bool) or not isinstance(requested, int) \
                or not 0 <= requested <= 232:
            raise ParameterError('ROS domain', requested, 'must be an integer within 0-232 '
                                 '(ROS 2 on Linux)')
        return DomainReservation(requested, None)
    candidates = list(DOMAINS)
    (rng or random.Random()).shuffle(candidates)
    for domain in candidates:
        sock = _bind(domain)
        if sock is not None:
            return DomainReservation(domain, sock)
    raise ParameterError('ROS domain', 'auto', f'no free domain within {DOMAINS.start}-'
                         f'{DOMAINS.stop - 1} on this host')
