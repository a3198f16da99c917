"""Residual learning: features, the batched MLP ensemble, training and the out-of-envelope guard.

The residual package uses the physics only through :class:`hybridship.physics.model.DynamicModel`.
"""
