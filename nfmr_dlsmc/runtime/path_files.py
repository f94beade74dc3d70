"""
Path files: the points of a path to follow (:mod:`nfmr_dlsmc.core.path_reference`).

Two formats, told apart by the file's suffix:

- CSV (any suffix but ``.yaml``/``.yml``): a header naming the columns, ``x,y`` [m] or
  ``t,x,y`` [s, m, m], each optionally with ``yaw`` [rad] (``x,y,yaw``, ``t,x,y,yaw``; in
  any order, any case, spaces around the commas allowed), then one point a line. Blank
  lines and ``#`` comments are skipped.
- YAML (``.yaml``/``.yml``): a list of points, or a mapping whose one key ``points`` holds
  that list. A point is ``[x, y]`` or ``[t, x, y]``, or a mapping ``{x: , y: }`` with
  optional keys ``t`` and ``yaw``.

The yaw is the robot's heading at the point, for a robot that may face another way than it
moves (:meth:`~nfmr_dlsmc.core.path_reference.PathTrajectory.from_points`, keyword
``yaw``): a path has it on every point or on none.

Both are UTF-8 text (a byte-order mark, as spreadsheets write it, is skipped), at most
:data:`MAX_FILE_SIZE`; only a regular file is read (not a device, FIFO or socket).

Every error is a :class:`PathFileError` naming the file, the line and the column, e.g.
``warehouse.csv line 5, column y: 'abc' is not a number``.
"""

from pathlib import Path
import stat

from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.core.path_reference import PathError, PathProfile, PathTrajectory
import numpy as np
import yaml

__all__ = ['MAX_FILE_SIZE', 'PathFileError', 'load_path', 'load_path_trajectory',
           'load_path_yaw']

#: Largest path file read [bytes]: 8 MiB, 400,000 points of CSV, 20 times the intervals a
#: path is resampled to at most. Such a CSV reads in 2 s; YAML, parsed 30 times slower, in
#: a minute and under 1 GB (a file without a limit, /dev/zero, would take all memory).
MAX_FILE_SIZE = 8 * 2 ** 20

#: The columns a path has: untimed and timed, in the order :func:`load_path` returns them.
_UNTIMED = ('x', 'y')
_TIMED = ('t', 'x', 'y')
#: The optional column of the robot's heading [rad].
_YAW = 'yaw'
#: Every column a path file may name.
_COLUMNS = _TIMED + (_YAW,)
#: What a CSV header must look like, for the messages.
_HEADER_HINT = ("the header names the columns: 'x,y' [m] or 't,x,y' [s, m, m], with 'yaw' "
                '[rad] or without')
#: What a YAML point is, for the messages.
_POINT_HINT = ('a point is a list [x, y] or [t, x, y], or a mapping {x: , y: } with t: [s] '
               'and yaw: [rad] or without')
#: What a YAML file must hold, for the messages.
_YAML_HINT = ('a list of points [x, y] or [t, x, y] or {x: , y: , yaw: } (or a mapping with '
              'the key points: holding it)')
#: Why the yaw is on every point or on none, for the messages.
_ALL_OR_NONE = 'a path has a yaw on every point or on none'
#: The files that are not regular files, by their type, as the messages name them.
_SPECIAL_FILES = {stat.S_IFCHR: 'a character device', stat.S_IFBLK: 'a block device',
                  stat.S_IFIFO: 'a FIFO', stat.S_IFSOCK: 'a socket'}


class PathFileError(NfmrError, ValueError):
    """
    A path file that cannot be read, or whose points do not make a path.

    Attributes
    ----------
    file : str
        The file as given.
    line : int or None
        The line at fault, 1 the first; None for the whole file.
    column : str or None
        The field at fault (``t``, ``x`` or ``y``), if one is.
    message : str
        What is wrong, without the place.

    """

    def __init__(self, file, message: str, line: int | None = None, column: str | None = None):
        self.file = str(file)
        self.line = line
        self.column = column
        self.message = message
        where = self.file
        if line is not None:
            where += f' line {line}'
        if column is not None:
            where += f', column {column}'
        super().__init__(f'{where}: {message}')

    def __reduce__(self):
        """Pickle with the arguments the constructor takes."""
        return type(self), (self.file, self.message, self.line, self.column)


def load_path(file) -> np.ndarray:
    """
    Return the points of a path file.

    Parameters
    ----------
    file : str or os.PathLike
        A CSV file, or YAML with the suffix ``.yaml`` or ``.yml`` (see the module docstring).

    Returns
    -------
    ndarray
        (N, 2) of x, y [m], or (N, 3) of t, x, y [s, m, m] for a timed path, whatever the
        order of the CSV columns; the rows in the file's order. A yaw column is checked but
        not returned (:func:`load_path_yaw` returns it).

    Raises
    ------
    PathFileError
        For a missing or unreadable file, a directory or another file that is not a regular
        one, one larger than :data:`MAX_FILE_SIZE`, an empty one, a missing or unknown
        column, a field that is not a finite number, rows of different lengths, or a yaw on
        some points but not all.

    """
    return _read(file)[0]


def load_path_yaw(file) -> tuple[np.ndarray, np.ndarray | None]:
    """
    Return the points of a path file and their yaws.

    Returns
    -------
    tuple
        The points as :func:`load_path` returns them, and (N,) yaws [rad] as the file gives
        them (not unwrapped), or None for a file without a yaw column.

    Raises
    ------
    PathFileError
        As :func:`load_path`.

    """
    points, headings, _ = _read(file)
    return points, headings


def load_path_trajectory(file, profile: PathProfile | None = None) -> PathTrajectory:
    """
    Return the reference along the points of a path file (:func:`load_path`).

    Raises
    ------
    PathFileError
        As :func:`load_path`, and for points that do not make a path (a cusp, stamps that
        do not increase, fewer than 2 distinct points), naming the line of the point.

    """
    points, headings, lines = _read(file)
    try:
        return PathTrajectory.from_points(points, profile, yaw=headings)
    except PathError as exc:
        line = None if exc.index is None else lines[exc.index]
        raise PathFileError(file, exc.rule, line) from None


def _read(file) -> tuple[np.ndarray, np.ndarray | None, list[int]]:
    """Return the points of ``file``, their yaws or None, and the line each comes from."""
    path = Path(file)
    try:
        text = _text(file, path)
    except FileNotFoundError:
        raise PathFileError(file, 'no such file') from None
    except UnicodeDecodeError:
        raise PathFileError(file, 'not a text file (not UTF-8)') from None
    except OSError as exc:
        raise PathFileError(file, f'cannot read: {exc.strerror or exc}') from None
    if path.suffix.lower() in ('.yaml', '.yml'):
        rows, lines, names = _yaml_rows(file, text)
    else:
        rows, lines, names = _csv_rows(file, text)
    order = [names.index(name) for name in (_TIMED if 't' in names else _UNTIMED)]
    table = np.array(rows, dtype=float)
    headings = table[:, names.index(_YAW)] if _YAW in names else None
    return table[:, order], headings, lines


def _text(file, path: Path) -> str:
    """
    Return the text of the regular file ``path``, refusing any other before opening it.

    At most :data:`MAX_FILE_SIZE` + 1 bytes are read, so that a file growing meanwhile (or
    one whose size the system does not tell, as under /proc) is refused all the same.
    """
    status = path.stat()
    if stat.S_ISDIR(status.st_mode):
        raise PathFileError(file, 'is a directory, expected a path file')
    if not stat.S_ISREG(status.st_mode):
        kind = _SPECIAL_FILES.get(stat.S_IFMT(status.st_mode), 'a special file')
        raise PathFileError(file, f'is not a regular file ({kind}), expected a path file')
    limit = f'larger than the {MAX_FILE_SIZE / 2 ** 20:g} MiB a path file may have'
    if status.st_size > MAX_FILE_SIZE:
        raise PathFileError(file, f'is {status.st_size / 2 ** 20:.1f} MiB, {limit}')
    with path.open('rb') as stream:
        data = stream.read(MAX_FILE_SIZE + 1)
    if len(data) > MAX_FILE_SIZE:
        raise PathFileError(file, f'is {limit}')
    return data.decode('utf-8-sig')


def _number(file, line: int, column: str, text: str) -> float:
    """Return the CSV field ``text`` as a finite float."""
    try:
        value = float(text)
    except ValueError:
        raise PathFileError(file, f'{text!r} is not a number', line, column) from None
    if not np.isfinite(value):
        raise PathFileError(file, f'{text!r} is not a finite number', line, column)
    return value


def _csv_rows(file, text: str):
    """Return the rows of a CSV path, their lines and the header's column names."""
    names = None
    header_line = None
    rows, lines = [], []
    for number, raw in enumerate(text.splitlines(), 1):
        cells = [cell.strip() for cell in raw.partition('#')[0].split(',')]
        if cells == ['']:
            continue
        if names is None:
            names = _header(file, number, cells)
            header_line = number
            continue
        if _YAW in names and (len(cells) == len(names) - 1 and names[-1] == _YAW
                              or len(cells) == len(names) and not cells[names.index(_YAW)]):
            raise PathFileError(file, f'no yaw, but the header (line {header_line}) names a '
                                f'yaw column: {_ALL_OR_NONE}', number, _YAW)
        if len(cells) != len(names):
            hint = ''
            if _YAW not in names and len(cells) == len(names) + 1:
                hint = f' (a yaw needs a yaw column in the header: {_ALL_OR_NONE})'
            raise PathFileError(file, f'{len(cells)} fields, but the header (line '
                                f"{header_line}) names {len(names)}: {','.join(names)}"
                                + hint, number)
        rows.append([_number(file, number, name, cell) for name, cell in zip(names, cells)])
        lines.append(number)
    if names is None:
        raise PathFileError(file, f'empty: no header and no points ({_HEADER_HINT})')
    if not rows:
        raise PathFileError(file, f'no points after the header (line {header_line})')
    return rows, lines, names


def _header(file, line: int, cells: list[str]) -> list[str]:
    """Return the column names of a CSV header line, checked."""
    names = [cell.lower() for cell in cells]
    if all(_is_number(cell) for cell in cells):
        raise PathFileError(file, f'no header: {_HEADER_HINT}, before the points', line)
    for name, cell in zip(names, cells):
        if name not in _COLUMNS:
            raise PathFileError(file, f'unknown column {cell!r}: {_HEADER_HINT}', line)
        if names.count(name) > 1:
            raise PathFileError(file, f'column {name} is named twice', line)
    for name in _UNTIMED:
        if name not in names:
            raise PathFileError(file, f'no column {name}: {_HEADER_HINT}', line)
    return names


def _is_number(text: str) -> bool:
    """Return whether ``text`` reads as a float."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def _yaml_rows(file, text: str):
    """Return the rows of a YAML path, their lines and the column names."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        problem = getattr(exc, 'problem', None) or str(exc)
        raise PathFileError(file, f'YAML syntax error: {problem}',
                            None if mark is None else mark.line + 1) from None
    if node is None:
        raise PathFileError(file, f'empty: expected {_YAML_HINT}')
    if isinstance(node, yaml.MappingNode):
        node = _points_entry(file, node)
    if not isinstance(node, yaml.SequenceNode) or not node.value:
        raise PathFileError(file, f'expected {_YAML_HINT}', node.start_mark.line + 1)
    constructor = yaml.constructor.SafeConstructor()
    rows, lines = [], []
    names = None
    for item in node.value:
        line = item.start_mark.line + 1
        if isinstance(item, yaml.MappingNode):
            fields = _yaml_fields(file, item)
        elif isinstance(item, yaml.SequenceNode) and len(item.value) in (2, 3):
            fields = dict(zip(_UNTIMED if len(item.value) == 2 else _TIMED, item.value))
        else:
            raise PathFileError(file, _POINT_HINT, line)
        if names is None:
            names = [name for name in _COLUMNS if name in fields]
            first_line = line
        elif (_YAW in fields) != (_YAW in names):
            what = ('no yaw, but the first point (line {}) has one' if _YAW in names else
                    'a yaw, but the first point (line {}) has none').format(first_line)
            raise PathFileError(file, f'{what}: {_ALL_OR_NONE}', line, _YAW)
        elif set(fields) != set(names):
            if isinstance(item, yaml.SequenceNode):
                what = (f'{len(fields)} numbers, but the first point (line {first_line}) has '
                        f'{len(names)}: [{", ".join(names)}]')
            else:
                what = (f'keys {", ".join(fields)}, but the first point (line {first_line}) '
                        f'has {", ".join(names)}')
            raise PathFileError(file, what, line)
        rows.append([_yaml_number(file, constructor, name, fields[name]) for name in names])
        lines.append(line)
    return rows, lines, list(names)


def _yaml_fields(file, item) -> dict:
    """Return the values of a YAML point given as a mapping, by their keys, checked."""
    fields = {}
    for key, value in item.value:
        name = key.value if isinstance(key, yaml.ScalarNode) else None
        line = key.start_mark.line + 1
        if name not in _COLUMNS:
            raise PathFileError(file, f'unknown key {name!r}: {_POINT_HINT}', line)
        if name in fields:
            raise PathFileError(file, f'key {name} given twice', line, name)
        fields[name] = value
    for name in _UNTIMED:
        if name not in fields:
            raise PathFileError(file, f'no key {name}: {_POINT_HINT}',
                                item.start_mark.line + 1)
    return fields


def _points_entry(file, node):
    """Return the value of the key ``points`` of a YAML mapping, the only key allowed."""
    found = None
    for key, value in node.value:
        name = key.value if isinstance(key, yaml.ScalarNode) else None
        if name != 'points':
            raise PathFileError(file, f'unknown key {name!r}: expected {_YAML_HINT}',
                                key.start_mark.line + 1)
        found = value
    if found is None:
        raise PathFileError(file, f'no key points: expected {_YAML_HINT}',
                            node.start_mark.line + 1)
    return found


def _yaml_number(file, constructor, name: str, scalar) -> float:
    """Return a YAML scalar as a finite float, as YAML types it (true is no number)."""
    line = scalar.start_mark.line + 1
    if not isinstance(scalar, yaml.ScalarNode):
        raise PathFileError(file, 'expected a number, found a list or mapping', line, name)
    value = constructor.construct_object(scalar)
    if isinstance(value, str) and scalar.style is None and _is_number(value):
        value = float(value)  # 1e3: YAML 1.1 reads a float only with a dot (1.0e3)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise PathFileError(file, f'{scalar.value!r} is not a number', line, name)
    try:
        value = float(value)
    except OverflowError:  # an integer of hundreds of digits
        value = np.inf
    if not np.isfinite(value):
        raise PathFileError(file, f'{scalar.value!r} is not a finite number', line, name)
    return value
