"""
The parameter reference of the nodes, ``doc/parameters.md``, generated from the schema.

``python -m nfmr_dlsmc.analysis.parameter_reference doc/parameters.md`` (``make docs``)
writes it; ``test/test_parameter_schema.py`` fails while the file in the tree differs from
what :func:`render` gives, so the reference never goes stale. The sim's parameters come
from the ``pybullet`` plant's registration (this package never imports ``nfmr_sim``).
"""

from pathlib import Path
import sys

from nfmr_dlsmc.core.schema import markdown_table
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.runtime.joint_states import wheel_odometry_parameters
from nfmr_dlsmc.runtime.params import controller_parameters

__all__ = ['render']

_HEADER = """\
# Parameters

Generated from the schema by `make docs`; do not edit by hand. Each parameter is declared
once, in the schema of its config class
([`nfmr_dlsmc/core/schema.py`](../nfmr_dlsmc/core/schema.py)): the nodes' declarations and
descriptors, the validation, the live-set rules and these tables derive from it. `ros2
param describe /controller <name>` (or `/sim`, `/wheel_odometry`) gives the same
description, unit and rule, and a numeric range for a rule that is an interval (`> 0` is
shown as 0 to inf, whose end 0 the rule still refuses), as rqt_reconfigure shows it.
Integers are accepted for floating-point parameters. A parameter marked live can be changed
while the node runs (`ros2 param set`): the change is validated like a parameter file and
applied at the next tick or physics step, or refused with the reason; the others are
read-only. What the nodes do with them: [nodes.md](nodes.md).
"""

_SECTIONS = (
    ('`controller`: the DLSMC node', controller_parameters),
    ('`sim`: the simulated robot', lambda: robot_plant('pybullet').node_parameters()),
    ('`wheel_odometry`: odometry from the wheel encoders', wheel_odometry_parameters),
)


def render() -> str:
    """Return the Markdown of ``doc/parameters.md``: a table per node."""
    parts = [_HEADER]
    for title, parameters in _SECTIONS:
        parts.append(f'## {title}\n\n{markdown_table(parameters())}')
    return '\n'.join(parts)


def main(argv=None) -> int:
    """Write :func:`render` to the file named in ``argv`` (default stdout); return 0."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) > 1:
        print('usage: python -m nfmr_dlsmc.analysis.parameter_reference [FILE]',
              file=sys.stderr)
        return 2
    text = render()
    if args:
        Path(args[0]).write_text(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
