"""Compare messages decoded by different libraries."""

import dataclasses


def plain(value):
    """
    Return a decoded message (rclpy, mcap_ros2, rosbags) as nested dicts and lists.

    Their leaves are numbers and strings, so that three decoders can be compared field by
    field.
    """
    if hasattr(value, 'get_fields_and_field_types'):  # rclpy
        return {k: plain(getattr(value, k)) for k in value.get_fields_and_field_types()}
    if dataclasses.is_dataclass(value):  # rosbags
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)
                if f.name != '__msgtype__' and not f.name.isupper()}
    if hasattr(value, '__slots__') and not isinstance(value, (str, bytes)):  # mcap_ros2
        # Its classes (like rosbags') also carry the message constants, named in upper case.
        return {k: plain(getattr(value, k)) for k in value.__slots__ if not k.isupper()}
    if isinstance(value, bytes) and len(value) == 1:  # rclpy's `byte` field
        return value[0]
    if isinstance(value, bytes):  # mcap_ros2's uint8[] (Marker.texture.data)
        return list(value)
    if isinstance(value, (list, tuple)) or hasattr(value, 'tolist'):
        return [plain(v) for v in (value.tolist() if hasattr(value, 'tolist') else value)]
    return value
