"""
The command-line programs: argument parsing and ``main`` of each ``nfmr-*`` command.

The top layer; may import any other.
"""
