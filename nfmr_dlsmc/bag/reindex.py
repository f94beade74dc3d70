"""
Rebuild a bag whose recorder died (``nfmr-reindex``), as ``ros2 bag reindex`` does: no rclpy.

A recorder killed with SIGKILL leaves an MCAP file without its summary and footer, cut in
its last chunk, and no ``metadata.yaml``; rosbag2 tools, ``rosbags`` and ``mcap_ros2``
refuse it. :func:`reindex` reads what the file holds up to its last complete chunk
(:mod:`~nfmr_dlsmc.bag.reader`), writes it as a finished MCAP file with a ``metadata.yaml``,
and keeps the original beside it as ``<file>.before-reindex``.
"""

from dataclasses import dataclass
from pathlib import Path
import shutil

from nfmr_dlsmc.bag.reader import BagContents, BagError, iter_bag, mcap_file
from nfmr_dlsmc.bag.writer import BagWriter
import yaml

#: What the original of a rebuilt bag file is kept as, beside it.
ORIGINAL_SUFFIX = '.before-reindex'


@dataclass(frozen=True)
class ReindexResult:
    """
    What :func:`reindex` did.

    Attributes
    ----------
    bag : Path
        The bag directory.
    rebuilt : bool
        False when the bag was complete and had its ``metadata.yaml``: nothing to do.
    messages, topics : int
        Messages and topics in the rebuilt file.
    lost_bytes : int
        Bytes of the cut last chunk that could not be recovered.
    original : Path or None
        Where the original file was kept.

    """

    bag: Path
    rebuilt: bool
    messages: int
    topics: int
    lost_bytes: int
    original: Path | None


def _profiles(metadata: dict) -> list:
    """Return the offered QoS profiles of a channel's metadata (rosbag2's YAML)."""
    try:
        profiles = yaml.safe_load(metadata.get('offered_qos_profiles', '') or '') or []
    except yaml.YAMLError:
        return []
    return [p for p in profiles if isinstance(p, dict)] if isinstance(profiles, list) else []


def reindex(path) -> ReindexResult:
    """
    Rebuild the bag at ``path`` (its directory, or its ``.mcap`` file) if it needs it.

    Raises
    ------
    BagError
        Not a bag, an MCAP file that holds no complete chunk, or a bag directory that
        cannot be written.

    """
    file = mcap_file(path)
    bag = file.parent
    contents = BagContents(path=file)
    for _ in iter_bag(file, topics=(), contents=contents):  # channels and truncation only
        pass
    damaged = contents.truncated or contents.corrupt_chunks
    if not damaged and (bag / 'metadata.yaml').is_file():
        return ReindexResult(bag, False, 0, len(contents.topics), 0, None)
    # The kept original of an earlier reindex is rebuilt again into the bag's own file,
    # and stays as it is: no second .mcap beside it, no .before-reindex.before-reindex.
    again = file.name.endswith(ORIGINAL_SUFFIX)
    name = file.name[:-len(ORIGINAL_SUFFIX)] if again else file.name
    stem = name[:-len('_0.mcap')] if name.endswith('_0.mcap') else Path(name).stem
    staging = bag.parent / f'.{bag.name}.reindexing'
    if staging.exists():
        shutil.rmtree(staging)
    try:
        messages = 0
        with BagWriter(staging, stem=stem) as writer:
            for message in iter_bag(file, contents=BagContents(path=file)):
                if message.topic not in writer.counts:
                    metadata = contents.topics.get(message.topic, ('', {}))[1]
                    writer.add_topic(message.topic, message.type_name, _profiles(metadata))
                writer.write(message.topic, message.log_time, message.data,
                             message.publish_time)
                messages += 1
        if not messages:
            raise BagError(f'{file}: no complete chunk to recover')
        original = file if again else file.with_name(file.name + ORIGINAL_SUFFIX)
        if not again:
            file.replace(original)
        writer.path.replace(bag / f'{stem}_0.mcap')
        (staging / 'metadata.yaml').replace(bag / 'metadata.yaml')
    except OSError as exc:
        raise BagError(f'{bag}: cannot rebuild the bag: {exc.strerror or exc}') from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return ReindexResult(bag, True, messages, len(writer.counts), contents.unread_bytes,
                         original)
