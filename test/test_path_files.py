"""Path files: CSV and YAML points, every error naming the file, line and column."""

import math
import os
from pathlib import Path
import pickle
import socket
import threading

from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.core.path_reference import PathError, PathProfile, PathTrajectory, stamped_points
from nfmr_dlsmc.runtime import path_files
from nfmr_dlsmc.runtime.params import controller_params
from nfmr_dlsmc.runtime.path_files import (
    load_path,
    load_path_trajectory,
    load_path_yaw,
    MAX_FILE_SIZE,
    PathFileError,
)
from nfmr_dlsmc.runtime.tracking_session import TrackingSession
from nfmr_dlsmc.runtime.user_errors import report_user_error, USER_ERROR_STATUS
import numpy as np
import pytest

PATHS = Path(__file__).resolve().parents[1] / 'config' / 'paths'


def _write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


# -- reading --------------------------------------------------------------------------------

def test_a_csv_path_with_comments_blank_lines_and_spaces(tmp_path):
    path = _write(tmp_path, 'aisle.csv', '# an aisle and back\n'
                                         '\n'
                                         '  x , y  \n'
                                         '0, 0\n'
                                         '  # a station\n'
                                         '2.5 ,0.0   # inline comment\n'
                                         '\n'
                                         '2.5, 1e0\n')
    points = load_path(path)
    np.testing.assert_array_equal(points, [[0.0, 0.0], [2.5, 0.0], [2.5, 1.0]])
    assert points.dtype == float


@pytest.mark.parametrize('header, row', [('t,x,y', '1.5,2,3'), ('x,y,t', '2,3,1.5'),
                                         ('Y, T, X', '3,1.5,2')])
def test_the_header_decides_the_columns_and_a_t_column_makes_a_timed_path(tmp_path, header,
                                                                          row):
    path = _write(tmp_path, 'timed.csv', f'{header}\n0,0,0\n{row}\n')
    points = load_path(path)
    assert points.shape == (2, 3)
    np.testing.assert_array_equal(points[1], [1.5, 2.0, 3.0])  # always t, x, y


def test_columns_in_another_order_come_back_as_x_y(tmp_path):
    points = load_path(_write(tmp_path, 'p.txt', 'y,x\n1,2\n3,4\n'))
    np.testing.assert_array_equal(points, [[2.0, 1.0], [4.0, 3.0]])


@pytest.mark.parametrize('name, text, expected', [
    ('list.yaml', '# x, y [m]\n- [0, 0]\n- [2.5, 0]\n- [2.5, 1]\n',
     [[0.0, 0.0], [2.5, 0.0], [2.5, 1.0]]),
    ('flow.yml', '[[0, 0], [1.5, -2e-1]]\n', [[0.0, 0.0], [1.5, -0.2]]),
    ('mapping.yaml', 'points:\n  - [0.0, 0.0]\n  - [3, 4]\n', [[0.0, 0.0], [3.0, 4.0]]),
    ('timed.YAML', 'points: [[0, 0, 0], [2.0, 1, 1]]\n', [[0.0, 0.0, 0.0], [2.0, 1.0, 1.0]]),
])
def test_a_yaml_path(tmp_path, name, text, expected):
    np.testing.assert_array_equal(load_path(_write(tmp_path, name, text)), expected)


@pytest.mark.parametrize('name, text', [('sheet.csv', '# from a spreadsheet\nx,y\n0,0\n1,2\n'),
                                        ('sheet.csv', 'x,y\n0,0\n1,2\n'),
                                        ('list.yaml', '- [0, 0]\n- [1, 2]\n')])
def test_a_byte_order_mark_is_skipped(tmp_path, name, text):
    path = tmp_path / name
    path.write_bytes(b'\xef\xbb\xbf' + text.encode())  # UTF-8 with BOM, as Excel saves it
    np.testing.assert_array_equal(load_path(path), [[0.0, 0.0], [1.0, 2.0]])


# -- errors ---------------------------------------------------------------------------------

CSV_ERRORS = [
    ('', None, None, 'empty: no header and no points'),
    ('# only a comment\n\n', None, None, 'empty: no header and no points'),
    ('x,y\n# nothing\n', None, None, 'no points after the header (line 1)'),
    ('0,0\n1,1\n', 1, None, "no header: the header names the columns: 'x,y' [m] or 't,x,y'"),
    ('x,z\n0,0\n', 1, None, "unknown column 'z'"),
    ('# x and t only\nt,x\n0,0\n', 2, None, 'no column y'),
    ('x,y,x\n0,0,0\n', 1, None, 'column x is named twice'),
    ('x,y\n0,0\n1,1\n2,2\nabc,3\n', 5, 'x', "'abc' is not a number"),
    ('# header next\nx,y\n0,0\n1,1,1\n', 4, None,
     '3 fields, but the header (line 2) names 2: x,y'),
    ('x,y\n0,0\n1\n', 3, None, '1 fields, but the header (line 1) names 2'),
    ('x,y\n0,0\n1,\n', 3, 'y', "'' is not a number"),
    ('t,x,y\n0,0,0\nnan,1,1\n', 3, 't', "'nan' is not a finite number"),
    ('x,y\n0,0\n1,-inf\n', 3, 'y', "'-inf' is not a finite number"),
    ('x,y\n0,0\n1e400,0\n', 3, 'x', "'1e400' is not a finite number"),
]


def test_text_in_a_number_reads_as_the_brief_says(tmp_path):
    _write(tmp_path, 'warehouse.csv', 'x,y\n0,0\n1,0\n2,0\n3,abc\n')
    with pytest.raises(PathFileError) as caught:
        load_path(tmp_path / 'warehouse.csv')
    assert str(caught.value) == f"{tmp_path}/warehouse.csv line 5, column y: 'abc' is not a number"


YAML_ERRORS = [
    ('', None, None, 'empty: expected a list of points [x, y] or [t, x, y]'),
    ('- [0, 0]\n- [1, 1\n', 3, None, 'YAML syntax error'),
    ('frame: map\npoints: [[0, 0], [1, 1]]\n', 1, None, "unknown key 'frame'"),
    ('{}\n', 1, None, 'no key points'),
    ("- [0, 0]\n- [1, '2']\n", 2, 'y', "'2' is not a number"),
    ('points: 3\n', 1, None, 'expected a list of points'),
    ('- [0, 0]\n- [1, abc]\n', 2, 'y', "'abc' is not a number"),
    ('- [0, 0]\n- [true, 1]\n', 2, 'x', "'true' is not a number"),
    ('- [0, 0]\n- [.nan, 1]\n', 2, 'x', "'.nan' is not a finite number"),
    ('- [0, 0]\n- [1, [2]]\n', 2, 'y', 'expected a number, found a list or mapping'),
    # An integer past the floats.
    (f'- [0, 0]\n- [1{"0" * 400}, 1]\n', 2, 'x', f"'1{'0' * 400}' is not a finite number"),
    ('- [0, 0]\n- [0, 1, 1]\n', 2, None, '3 numbers, but the first point (line 1) has 2: '
                                         '[x, y]'),
    ('- [0, 0, 0, 0]\n', 1, None, 'a point is a list [x, y] or [t, x, y]'),
    ('- 1\n- 2\n', 1, None, 'a point is a list [x, y] or [t, x, y]'),
]


@pytest.mark.parametrize('name, text, line, column, message',
                         [('warehouse.csv', *case) for case in CSV_ERRORS]
                         + [('route.yaml', *case) for case in YAML_ERRORS])
def test_a_bad_file_is_refused_naming_the_line_and_column(tmp_path, name, text, line, column,
                                                          message):
    path = _write(tmp_path, name, text)
    with pytest.raises(PathFileError) as caught:
        load_path(path)
    where = f'{path}' + (f' line {line}' if line else '') + (f', column {column}' if column
                                                             else '')
    assert str(caught.value).startswith(f'{where}: {message}')
    error = caught.value
    assert (error.file, error.line, error.column) == (str(path), line, column)


def test_a_missing_file_or_a_folder_is_refused_naming_it(tmp_path):
    with pytest.raises(PathFileError, match=f'^{tmp_path}/missing.csv: no such file$'):
        load_path(tmp_path / 'missing.csv')
    with pytest.raises(PathFileError, match=f'^{tmp_path}: is a directory'):
        load_path(tmp_path)
    (tmp_path / 'binary.csv').write_bytes(b'x,y\n\xff\xfe\n')
    with pytest.raises(PathFileError, match='not a text file'):
        load_path(tmp_path / 'binary.csv')


def _refusal(path) -> str:
    """Return the message load_path refuses ``path`` with, within 10 s (a FIFO may block)."""
    found = []

    def load():
        with pytest.raises(PathFileError) as caught:
            load_path(path)
        found.append(str(caught.value))

    worker = threading.Thread(target=load, daemon=True)
    worker.start()
    worker.join(10.0)
    if worker.is_alive():  # blocked opening the FIFO: a writer lets it go
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
        worker.join(10.0)
        pytest.fail(f'load_path({path}) blocked')
    assert found, 'no PathFileError'
    return found[0]


@pytest.mark.parametrize('kind', ['a character device', 'a FIFO', 'a socket'])
def test_only_a_regular_file_is_read(tmp_path, monkeypatch, kind):
    monkeypatch.chdir(tmp_path)  # a socket's path is short: 108 bytes at most
    if kind == 'a character device':
        path = '/dev/zero'  # read whole, it would take all memory
    elif kind == 'a FIFO':
        path = 'route.csv'
        os.mkfifo(path)  # opened, it would wait for a writer
    else:
        path = 'route.csv'
        server = socket.socket(socket.AF_UNIX)
        server.bind(path)
        server.close()
    assert _refusal(path) == f'{path}: is not a regular file ({kind}), expected a path file'


def test_a_file_larger_than_the_limit_is_refused_unread(tmp_path, monkeypatch):
    with open(tmp_path / 'huge.csv', 'wb') as stream:
        stream.truncate(MAX_FILE_SIZE + 1)  # sparse: no disk space taken
    assert MAX_FILE_SIZE == 8 * 2 ** 20
    with pytest.raises(PathFileError, match=r'huge.csv: is 8.0 MiB, larger than the 8 MiB a '
                                            'path file may have$'):
        load_path(tmp_path / 'huge.csv')
    path = _write(tmp_path, 'l.csv', 'x,y\n0,0\n4,0\n')  # 12 bytes
    monkeypatch.setattr(path_files, 'MAX_FILE_SIZE', 12)
    assert load_path(path).shape == (2, 2)  # as large as allowed
    monkeypatch.setattr(path_files, 'MAX_FILE_SIZE', 11)
    with pytest.raises(PathFileError, match='l.csv: is 0.0 MiB, larger than the 1.04904e-05 '
                                            'MiB'):
        load_path(path)


def test_a_file_longer_than_its_size_says_is_read_only_up_to_the_limit(monkeypatch):
    # Files under /proc say they are empty, as one growing while read would be larger.
    assert os.stat('/proc/self/maps').st_size == 0
    monkeypatch.setattr(path_files, 'MAX_FILE_SIZE', 100)
    assert _refusal('/proc/self/maps') == ('/proc/self/maps: is larger than the 9.53674e-05 MiB '
                                           'a path file may have')


def test_a_path_file_error_is_a_user_error_of_one_line(tmp_path, capsys):
    path = _write(tmp_path, 'warehouse.csv', 'x,y\n0,zero\n')
    with pytest.raises(NfmrError) as caught:
        load_path(path)
    assert isinstance(caught.value, ValueError)
    assert report_user_error('nfmr-run', caught.value) == USER_ERROR_STATUS
    assert capsys.readouterr().err == (f"nfmr-run: error: {path} line 2, column y: 'zero' is "
                                       'not a number\n')
    again = pickle.loads(pickle.dumps(caught.value))
    assert str(again) == str(caught.value) and again.line == 2 and again.column == 'y'


def test_points_that_make_no_path_are_refused_naming_their_line(tmp_path):
    path = _write(tmp_path, 'cusp.csv', 'x,y\n0,0\n# back again\n3,0\n3,0.0005\n1,0\n')
    with pytest.raises(PathFileError) as caught:
        load_path_trajectory(path)
    assert str(caught.value) == (f'{path} line 4: point 1 at (3.00, 0.00) m: the path turns '
                                 'back on itself (a cusp, a turn of 180 deg > 170 deg); '
                                 'reversing is not supported')
    path = _write(tmp_path, 'late.yaml', '- [0, 0, 0]\n- [1, 1, 0]\n- [1, 2, 0]\n')
    with pytest.raises(PathFileError, match=r'late.yaml line 3: point 2 .* stamps must'):
        load_path_trajectory(path)
    path = _write(tmp_path, 'one.csv', 'x,y\n1,1\n1,1\n')
    with pytest.raises(PathFileError, match=r'one.csv: 1 distinct point\(s\) \(2 given'):
        load_path_trajectory(path)


def test_huge_numbers_are_refused_naming_their_line(tmp_path):
    path = _write(tmp_path, 'far.csv', 'x,y\n0,0\n# far away\n1e200,0\n')
    with pytest.raises(PathFileError) as caught:
        load_path_trajectory(path)  # not scipy's "dydx must contain only finite values"
    assert str(caught.value) == (f'{path} line 4: point 1 at (1e+200, 0.00) m: a coordinate is '
                                 'beyond +-1e+08 m, farther than any map reaches (are the units '
                                 'metres?)')
    path = _write(tmp_path, 'late.yaml', '- [0, 0, 0]\n- [1.0e+300, 1, 1]\n')
    with pytest.raises(PathFileError, match=r'late.yaml line 2: point 1 at \(1.00, 1.00\) m: '
                                            r'its stamp 1e\+300 s is after 1e\+09 s'):
        load_path_trajectory(path)


def test_stamps_faster_than_the_robot_are_refused_naming_their_line(tmp_path):
    path = _write(tmp_path, 'dash.csv', 't,x,y\n0,0,0\n1,1,0\n1.000000001,2,0\n')
    with pytest.raises(PathFileError) as caught:
        load_path_trajectory(path)
    assert str(caught.value) == (f'{path} line 4: point 2 at (2.00, 0.00) m: the stamps ask '
                                 'for 1e+09 m/s between this point and the one before (1 m in '
                                 "1e-09 s); the robot's v_max is 2 m/s")
    path = _write(tmp_path, 'walk.csv', 't,x,y\n0,0,0\n1,1,0\n2.25,2,0\n')
    slow = PathProfile(v_max=0.8)
    with pytest.raises(PathFileError, match=r'walk.csv line 3: .* ask for 1 m/s .* v_max is '
                                            '0.8 m/s'):
        load_path_trajectory(path, slow)
    path = _write(tmp_path, 'walk.csv', 't,x,y\n0,0,0\n1.25,1,0\n2.5,2,0\n')
    assert load_path_trajectory(path, slow).duration == 2.5  # 0.8 m/s: as fast as it goes


def test_the_speed_limit_of_timed_paths_is_the_controllers_v_max(tmp_path):
    path = _write(tmp_path, 'walk.csv', 't,x,y\n0,0,0\n1,1,0\n')
    values = {'trajectory.name': 'path', 'trajectory.path.file': str(path)}
    assert controller_params(values).trajectory.duration == 1.0  # 1 m/s, v_max 2 m/s
    slow = values | {'limits.v_max': 0.8}
    with pytest.raises(PathFileError, match=r"walk.csv line 3: .* the robot's v_max is 0.8 m/s"):
        controller_params(slow)  # nfmr-eval, nfmr-run, the controller node's file
    params = controller_params(slow | {'trajectory.name': 'line'})
    assert params.path_profile.v_max == 0.8
    session = TrackingSession(params, odom_timeout=0.25)
    with pytest.raises(PathError, match=r"point 1 .* the robot's v_max is 0.8 m/s"):
        session.path_reference(stamped_points([(0.0, 0.0), (1.0, 0.0)], [3.0, 4.0]))  # a Path


def test_a_path_file_gives_its_trajectory(tmp_path):
    path = _write(tmp_path, 'l.csv', 'x,y\n0,0\n4,0\n4,3\n')
    profile = PathProfile(speed=0.8, corner_radius=0.5)
    traj = load_path_trajectory(path, profile)
    assert traj.profile is profile
    np.testing.assert_array_equal(traj.points, [[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]])
    assert traj.end_pose == pytest.approx((4.0, 3.0, math.pi / 2.0))


# -- headings -------------------------------------------------------------------------------

@pytest.mark.parametrize('name, text, points, yaw', [
    ('spin.csv', 'x,y,yaw\n0,0,0\n0,0,1.5708\n2,0,1.5708\n',
     [[0.0, 0.0], [0.0, 0.0], [2.0, 0.0]], [0.0, 1.5708, 1.5708]),
    ('order.csv', ' YAW , y, X\n-1,2,1\n0.5,3,4  # a comment\n', [[1.0, 2.0], [4.0, 3.0]],
     [-1.0, 0.5]),
    ('timed.csv', 't,x,y,yaw\n0,0,0,0\n2,1,0,1\n', [[0.0, 0.0, 0.0], [2.0, 1.0, 0.0]],
     [0.0, 1.0]),
    ('timed.txt', 'yaw,t,y,x\n0,0,0,0\n1,2,0,1\n', [[0.0, 0.0, 0.0], [2.0, 1.0, 0.0]],
     [0.0, 1.0]),
    ('map.yaml', 'points:\n  - {x: 0, y: 0, yaw: 0}\n  - {yaw: 1.5708, y: 0, x: 0}\n'
                 '  - {x: 2, y: 0, yaw: 1.5708}\n',
     [[0.0, 0.0], [0.0, 0.0], [2.0, 0.0]], [0.0, 1.5708, 1.5708]),
    ('timed.yml', '- {t: 0, x: 0, y: 0, yaw: 0.0}\n- {t: 2.0, x: 1, y: 0, yaw: 1e0}\n',
     [[0.0, 0.0, 0.0], [2.0, 1.0, 0.0]], [0.0, 1.0]),
    ('mixed forms.yaml', '- [0, 0]\n- {x: 1, y: 2}\n', [[0.0, 0.0], [1.0, 2.0]], None),
])
def test_a_yaw_column_or_key_gives_the_headings(tmp_path, name, text, points, yaw):
    path = _write(tmp_path, name, text)
    got, headings = load_path_yaw(path)
    np.testing.assert_array_equal(got, points)
    np.testing.assert_array_equal(load_path(path), points)  # load_path leaves the yaw out
    if yaw is None:
        assert headings is None
    else:
        np.testing.assert_array_equal(headings, yaw)
    assert load_path_trajectory(path).has_yaw == (yaw is not None)


def test_a_path_file_without_yaw_has_no_headings(tmp_path):
    points, headings = load_path_yaw(_write(tmp_path, 'p.csv', 'x,y\n0,0\n1,0\n'))
    assert headings is None and points.shape == (2, 2)


def test_a_file_with_yaw_gives_the_heading_reference(tmp_path):
    path = _write(tmp_path, 'spin.csv', '# spin on the spot, then drive facing +y\n'
                                        'x,y,yaw\n0,0,0\n0,0,1.5708\n2,0,1.5708\n')
    traj = load_path_trajectory(path)
    assert traj.yaw_reference(-1.0) == (0.0, 0.0)
    assert traj.yaw_reference(traj.duration) == (1.5708, 0.0)
    assert traj.sample(1.0) == (0.0, 0.0, 0.0, 0.0)  # spinning on the spot
    assert 0.0 < traj.yaw_reference(1.0)[0] < 1.5708


def test_a_byte_order_mark_before_a_yaw_header_is_skipped(tmp_path):
    path = tmp_path / 'sheet.csv'
    path.write_bytes(b'\xef\xbb\xbf' + 'x,y,yaw\r\n0,0,0\r\n1,2,3\r\n'.encode())
    points, headings = load_path_yaw(path)
    np.testing.assert_array_equal(points, [[0.0, 0.0], [1.0, 2.0]])
    np.testing.assert_array_equal(headings, [0.0, 3.0])


YAW_ERRORS = [
    ('p.csv', 'x,y,yaw\n0,0,0\n1,0,nan\n', 3, 'yaw', "'nan' is not a finite number"),
    ('p.csv', 'x,y,yaw\n0,0,0\n1,0,-inf\n', 3, 'yaw', "'-inf' is not a finite number"),
    ('p.csv', 'x,y,yaw\n0,0,0\n1,0,north\n', 3, 'yaw', "'north' is not a number"),
    ('p.csv', 'x,y,yaw\n0,0,0\n1,0,\n', 3, 'yaw',
     'no yaw, but the header (line 1) names a yaw column: a path has a yaw on every point or '
     'on none'),
    ('p.csv', 'x,y,yaw\n0,0,0\n1,0\n', 3, 'yaw', 'no yaw, but the header (line 1) names'),
    ('p.csv', 'x,yaw,y\n0,0,0\n1,,0\n', 3, 'yaw', 'no yaw, but the header (line 1) names'),
    ('p.csv', 'x,y\n0,0\n1,0,1.5\n', 3, None,
     '3 fields, but the header (line 1) names 2: x,y (a yaw needs a yaw column in the header: '
     'a path has a yaw on every point or on none)'),
    ('p.csv', 'x,y,heading\n0,0,0\n', 1, None, "unknown column 'heading'"),
    ('p.csv', 'x,y,yaw,YAW\n0,0,0,0\n', 1, None, 'column yaw is named twice'),
    ('p.yaml', '- {x: 0, y: 0, yaw: 0}\n- {x: 1, y: 0}\n', 2, 'yaw',
     'no yaw, but the first point (line 1) has one: a path has a yaw on every point or on '
     'none'),
    ('p.yaml', 'points:\n- [0, 0]\n- {x: 1, y: 0, yaw: 1}\n', 3, 'yaw',
     'a yaw, but the first point (line 2) has none'),
    ('p.yaml', '- {x: 0, y: 0, yaw: 0}\n- {x: 1, y: 0, yaw: .nan}\n', 2, 'yaw',
     "'.nan' is not a finite number"),
    ('p.yaml', '- {x: 0, y: 0, yaw: 0}\n- {x: 1, y: 0, yaw: [1]}\n', 2, 'yaw',
     'expected a number, found a list or mapping'),
    ('p.yaml', '- {x: 0, y: 0, psi: 0}\n', 1, None, "unknown key 'psi': a point is a list"),
    ('p.yaml', '- {x: 0, yaw: 0}\n', 1, None, 'no key y: a point is a list'),
    ('p.yaml', '- {x: 0, y: 0, x: 1}\n', 1, 'x', 'key x given twice'),
    ('p.yaml', '- {t: 0, x: 0, y: 0}\n- {x: 1, y: 0}\n', 2, None,
     'keys x, y, but the first point (line 1) has t, x, y'),
    ('p.yaml', '- {x: 0, y: 0}\n- [0, 1, 1]\n', 2, None,
     '3 numbers, but the first point (line 1) has 2: [x, y]'),
]


@pytest.mark.parametrize('name, text, line, column, message', YAW_ERRORS)
def test_a_bad_or_missing_yaw_is_refused_naming_the_line_and_column(tmp_path, name, text, line,
                                                                    column, message):
    path = _write(tmp_path, name, text)
    for load in (load_path, load_path_yaw, load_path_trajectory):
        with pytest.raises(PathFileError) as caught:
            load(path)
        where = f'{path} line {line}' + (f', column {column}' if column else '')
        assert str(caught.value).startswith(f'{where}: {message}')
        assert (caught.value.line, caught.value.column) == (line, column)


def test_a_turn_faster_than_the_robot_is_refused_naming_its_line(tmp_path):
    path = _write(tmp_path, 'fast.csv', 't,x,y,yaw\n0,0,0,0\n# then\n1,1,0,2.5\n')
    with pytest.raises(PathFileError, match=r'fast.csv line 4: point 1 at \(1.00, 0.00\) m: the '
                                            r'stamps ask for a yaw rate of 2.5 rad/s'):
        load_path_trajectory(path)
    assert load_path_trajectory(path, PathProfile(omega_max=2.5)).has_yaw


# -- the shipped examples -------------------------------------------------------------------

def _smallest_radius(traj: PathTrajectory) -> float:
    _, _, _, kappa = traj.geometry(np.linspace(0.0, traj.length, 400001))
    return 1.0 / np.abs(kappa).max()


def test_the_warehouse_loop():
    points = load_path(PATHS / 'warehouse_loop.csv')
    assert points.shape[1] == 2
    traj = PathTrajectory.from_points(points)
    assert traj.length == pytest.approx(25.0, abs=1.0)
    assert traj.start_pose == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)  # at (0, 0) heading +x
    x, y, _ = traj.end_pose
    assert 0.5 <= math.hypot(x, y) <= 1.5  # stops short of the start, on the last aisle
    # Straight aisles and 90 deg corners rounded with the default corner radius.
    turns = np.degrees(np.abs(np.diff(np.unwrap(np.arctan2(*np.diff(points, axis=0).T[::-1])))))
    assert sorted(set(np.round(turns))) == [0.0, 90.0]
    assert _smallest_radius(traj) >= PathProfile().corner_radius * (1.0 - 1e-3)


def test_the_field_coverage():
    text = (PATHS / 'field_coverage.csv').read_text()
    assert text.startswith('#')
    points = load_path(PATHS / 'field_coverage.csv')
    traj = PathTrajectory.from_points(points)
    assert traj.length == pytest.approx(40.0, abs=2.0)
    assert _smallest_radius(traj) >= 1.0
    # Rows along x, 2 m apart, driven in turn in both directions.
    rows = sorted({round(y, 6) for x, y in points if abs(x) < 1e-9 or abs(x - 8.0) < 1e-9})
    assert rows == [0.0, 2.0, 4.0]
    assert traj.start_pose == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert traj.end_pose == pytest.approx((8.0, 4.0, 0.0), abs=1e-9)
