"""
The comparison laws, their gains and the registry that builds any controller by name.

May import :mod:`nfmr_dlsmc.core` (and PyYAML for gain files).
"""
