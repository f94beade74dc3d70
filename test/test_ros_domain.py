"""A run's own ROS domain: reserved by a bound discovery port, never one already taken."""

import os
import random
import socket
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.ros_domain import (
    discovery_port,
    DOMAINS,
    FASTDDS_PROFILE,
    reserve_domain,
)
from nfmr_dlsmc.runtime.share import shipped_config
import pytest

VARIABLE, PROFILE = FASTDDS_PROFILE


def test_a_reserved_domain_is_held_until_released(monkeypatch):
    monkeypatch.delenv(VARIABLE, raising=False)
    first = reserve_domain(rng=random.Random(1))
    try:
        assert first.domain in DOMAINS
        assert first.environment() == {'ROS_DOMAIN_ID': str(first.domain),
                                       'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST',
                                       VARIABLE: str(shipped_config(PROFILE))}
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


def test_a_fast_dds_profile_the_user_names_is_kept(monkeypatch, tmp_path):
    own = tmp_path / 'mine.xml'
    monkeypatch.setenv(VARIABLE, str(own))
    assert reserve_domain(7).environment()[VARIABLE] == str(own)


@pytest.mark.ros
def test_the_run_profile_announces_often_suppresses_nacks_and_fast_dds_takes_it():
    root = ElementTree.parse(shipped_config(PROFILE)).getroot()
    ns = {'dds': 'http://www.eprosima.com'}

    def seconds(element):
        nanoseconds = int(element.find('dds:nanosec', ns).text)
        return int(element.find('dds:sec', ns).text) + nanoseconds * 1e-9

    assert 0.0 < seconds(root.find('.//dds:leaseAnnouncement', ns)) <= 0.5  # [s] default 3 s
    # Every writer's (the default profile's) window: a publish does not wake the event
    # thread each time, and a lost sample is still repaired within milliseconds (D23).
    writer = root.find("dds:profiles/dds:data_writer[@is_default_profile='true']", ns)
    assert 0.0 < seconds(writer.find('dds:times/dds:nackSupressionDuration', ns)) <= 0.01
    # A participant made with it: Fast DDS names any profile it cannot read on stderr.
    env = {**os.environ, **reserve_domain(9).environment(), VARIABLE: str(
        shipped_config(PROFILE))}
    made = subprocess.run([sys.executable, '-c', 'import rclpy; rclpy.init(); '
                           'from std_msgs.msg import Bool; '
                           "rclpy.create_node('profile_check').create_publisher(Bool, 'b', 10); "
                           "print('made')"],
                          env=env, capture_output=True, text=True, timeout=60)
    assert made.returncode == 0 and made.stdout.strip() == 'made', made.stderr
    assert 'XMLPARSER' not in made.stderr and 'Error' not in made.stderr, made.stderr
