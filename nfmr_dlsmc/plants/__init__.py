"""
Plants a controller drives in one process.

The kinematic model, the batch model, and robot simulators registered by other packages
(:mod:`nfmr_dlsmc.plants.registry`). May import :mod:`nfmr_dlsmc.core` (and scipy); never a
simulator package directly.
"""
