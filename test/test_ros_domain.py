"""A run's own ROS domain: reserved by a bound discovery port, never one already taken."""

import random
import socket

from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.ros_domain import discovery_port, DOMAINS, reserve_domain
import pytest


def test_a_reserved_domain_is_held_until_released():
    first = reserve_domain(rng=random.Random(1))
    try:
        assert first.domain in DOMAINS
        assert first.environment() == {'ROS_DOMAIN_ID': str(first.domain),
                                       'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}
        probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        with pytest.raises(OSError):  # taken: its first discovery port is bound
            probe.bind(('0.0.0.0', discovery_port(first.domain)))
        probe.close()
        # The same draw again must take another domain while the first is held.
        second = reserve_domain(rng=random.Random(1))
        assert second.domain != first.domain
        second.release()
    finally:
        first.release()
        first.release()  # idempotent
    again = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    again.bind(('0.0.0.0', discovery_port(first.domain)))  # free once released
    again.close()


def test_the_port_is_that_of_the_rtps_mapping():
    assert discovery_port(0) == 7410 and discovery_port(42) == 7400 + 250 * 42 + 10


@pytest.mark.parametrize('domain', [-1, 233, 300, True])
def test_a_domain_outside_what_ros_allows_is_refused(domain):
    with pytest.raises(ParameterError, match='ROS domain'):
        reserve_domain(domain)


def test_a_requested_domain_is_taken_as_it_is():
    assert reserve_domain(7).domain == 7
