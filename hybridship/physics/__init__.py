"""Batch-first physics core: hull (eq. 1), actuators (eq. 2, four-quadrant propellers), wind (eq. 3), integrator.

Nothing in this package imports torch.
"""
