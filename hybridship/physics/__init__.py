"""Batch-first physics core: hull (eq. 1), actuators (eq. 2, four-quadrant propellers), wind (eq. 3), integrator.

Nothing in this package imports torch.
"""

from .compiled_cache import drop_stale_compiled_kernels

# Every kernel module imports this package first, so this runs before anything compiles.
drop_stale_compiled_kernels()
