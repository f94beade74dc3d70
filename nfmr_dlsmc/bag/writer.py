"""
rosbag2-compatible MCAP bags: schemas, channel metadata, the rosbag2 record, metadata.yaml.

ROS-free (no rclpy): message definitions and type hashes come from the ``.msg`` and
``.json`` files that ROS interface packages install under ``share/<pkg>/msg/``; payloads
are the CDR bytes as published. A bag is a directory ``<name>/`` holding
``<name>_0.mcap`` and a version-9 ``metadata.yaml``, so ``ros2 bag info/play``, the
``rosbags`` library, Foxglove and PlotJuggler open it.
"""

from dataclasses import dataclass, field
import json
from pathlib import Path

from mcap.writer import CompressionType, Writer
from nfmr_dlsmc.runtime.share import share_directory
import yaml

ROS_DISTRO = 'jazzy'
_RULE = '=' * 80


def _interface_file(type_name: str, suffix: str) -> Path:
    pkg, kind, name = type_name.split('/')
    path = share_directory(pkg) / kind / f'{name}{suffix}'
    if not path.is_file():
        raise FileNotFoundError(f'no {suffix} file for {type_name}: {path}')
    return path


def message_definition(type_name: str) -> str:
    """
    Return the ``ros2msg`` schema text of ``pkg/msg/Type``.

    Its ``.msg`` followed by every type it references, each after a line of 80 ``=`` and
    ``MSG: pkg/Type`` (as rosbag2 writes).
    """
    text = _interface_file(type_name, '.msg').read_text()
    description = json.loads(_interface_file(type_name, '.json').read_text())
    referenced = [d['type_name'] for d in
                  description['type_description_msg']['referenced_type_descriptions']]
    parts = [text.rstrip('\n')]
    for dep in referenced:
        pkg, _, name = dep.split('/')
        parts.append(f'{_RULE}\nMSG: {pkg}/{name}\n'
                     f"{_interface_file(dep, '.msg').read_text().rstrip(chr(10))}")
    return '\n'.join(parts) + '\n'


def type_hash(type_name: str) -> str:
    """Return the RIHS01 type description hash of ``pkg/msg/Type``."""
    description = json.loads(_interface_file(type_name, '.json').read_text())
    for entry in description['type_hashes']:
        if entry['type_name'] == type_name:
            return entry['hash_string']
    raise KeyError(f'no type hash for {type_name}')


@dataclass(frozen=True)
class QosProfile:
    """An offered QoS profile as rosbag2 stores it (names lower-case, durations sec/nsec)."""

    history: str = 'keep_last'
    depth: int = 100
    reliability: str = 'reliable'
    durability: str = 'volatile'
    deadline: tuple = (9223372036, 854775807)
    lifespan: tuple = (9223372036, 854775807)
    liveliness: str = 'automatic'
    liveliness_lease_duration: tuple = (9223372036, 854775807)
    avoid_ros_namespace_conventions: bool = False

    def as_dict(self) -> dict:
        """Return the mapping of one entry of ``offered_qos_profiles``."""
        duration = lambda d: {'sec': int(d[0]), 'nsec': int(d[1])}  # noqa: E731
        return {'history': self.history, 'depth': self.depth, 'reliability': self.reliability,
                'durability': self.durability, 'deadline': duration(self.deadline),
                'lifespan': duration(self.lifespan), 'liveliness': self.liveliness,
                'liveliness_lease_duration': duration(self.liveliness_lease_duration),
                'avoid_ros_namespace_conventions': self.avoid_ros_namespace_conventions}


@dataclass
class _Topic:
    name: str
    type_name: str
    qos: list
    channel_id: int
    type_hash: str
    count: int = 0
    sequence: int = 0


@dataclass
class BagWriter:
    """
    Write one rosbag2 MCAP bag directory; use as a context manager.

    Parameters
    ----------
    directory : Path
        The bag directory to create (must not exist).
    chunk_size : int
        MCAP chunk size [bytes]; a killed recorder loses at most the open chunk.
    stem : str, optional
        The file is ``<stem>_0.mcap`` (default: the directory's name, as rosbag2 does).

    """

    directory: Path
    chunk_size: int = 1 << 20
    stem: str | None = None
    _topics: dict = field(default_factory=dict, init=False)
    _schemas: dict = field(default_factory=dict, init=False)
    _first: int | None = field(default=None, init=False)
    _last: int = field(default=0, init=False)
    _finished: bool = field(default=False, init=False)

    def __post_init__(self):
        self.directory = Path(self.directory)
        self.directory.mkdir(parents=True, exist_ok=False)
        self.path = self.directory / f'{self.stem or self.directory.name}_0.mcap'
        self._stream = self.path.open('wb')
        self._writer = Writer(self._stream, chunk_size=self.chunk_size,
                              compression=CompressionType.ZSTD)
        self._writer.start(profile='ros2', library='nfmr')
        # On disk at once: a bag whose recorder is killed before its first chunk is still an
        # MCAP file (magic and header), read as an empty, truncated bag.
        self._stream.flush()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.finish()

    def add_topic(self, name: str, type_name: str, qos: list) -> None:
        """
        Declare a topic before writing its messages (``type_name`` like ``pkg/msg/T``).

        ``qos``: :class:`QosProfile` objects, or mappings as rosbag2 stores them.
        """
        if name in self._topics:
            return
        if type_name not in self._schemas:
            self._schemas[type_name] = self._writer.register_schema(
                name=type_name, encoding='ros2msg',
                data=message_definition(type_name).encode())
        digest = type_hash(type_name)
        profiles = [q.as_dict() if isinstance(q, QosProfile) else dict(q) for q in qos]
        channel = self._writer.register_channel(
            topic=name, message_encoding='cdr', schema_id=self._schemas[type_name],
            metadata={'offered_qos_profiles': yaml.safe_dump(profiles, sort_keys=False).strip(),
                      'topic_type_hash': digest})
        self._topics[name] = _Topic(name, type_name, profiles, channel, digest)

    def write(self, topic: str, log_time_ns: int, data: bytes,
              publish_time_ns: int | None = None) -> None:
        """Append one serialized (CDR) message of a declared topic."""
        t = self._topics[topic]
        self._writer.add_message(t.channel_id, log_time=log_time_ns, data=data,
                                 publish_time=log_time_ns if publish_time_ns is None
                                 else publish_time_ns, sequence=t.sequence)
        t.sequence += 1
        t.count += 1
        if self._first is None or log_time_ns < self._first:
            self._first = log_time_ns
        self._last = max(self._last, log_time_ns)

    @property
    def counts(self) -> dict:
        """Return the messages written per topic."""
        return {name: t.count for name, t in self._topics.items()}

    def metadata(self) -> dict:
        """Return the ``rosbag2_bagfile_information`` mapping (version 9)."""
        start = self._first or 0
        duration = max(0, self._last - start)
        total = sum(t.count for t in self._topics.values())
        return {
            'version': 9, 'storage_identifier': 'mcap',
            'duration': {'nanoseconds': duration},
            'starting_time': {'nanoseconds_since_epoch': start},
            'message_count': total,
            'topics_with_message_count': [
                {'topic_metadata': {'name': t.name, 'type': t.type_name,
                                    'serialization_format': 'cdr',
                                    'offered_qos_profiles': t.qos,
                                    'type_description_hash': t.type_hash},
                 'message_count': t.count} for t in self._topics.values()],
            'compression_format': '', 'compression_mode': '',
            'relative_file_paths': [self.path.name],
            'files': [{'path': self.path.name,
                       'starting_time': {'nanoseconds_since_epoch': start},
                       'duration': {'nanoseconds': duration}, 'message_count': total}],
            'custom_data': None, 'ros_distro': ROS_DISTRO}

    def finish(self) -> None:
        """Write the rosbag2 record, the summary and ``metadata.yaml`` (idempotent)."""
        if self._finished:
            return
        self._finished = True
        info = self.metadata()
        self._writer.add_metadata('rosbag2', {
            'serialized_metadata': yaml.safe_dump(info, sort_keys=False),
            'ROS_DISTRO': ROS_DISTRO})
        self._writer.finish()
        self._stream.close()
        text = yaml.safe_dump({'rosbag2_bagfile_information': info}, sort_keys=False)
        tmp = self.directory / 'metadata.yaml.tmp'
        tmp.write_text(text)
        tmp.replace(self.directory / 'metadata.yaml')
