"""Residual learning: features, the batched MLP ensemble, training and the out-of-envelope guard.

The residual package uses the physics through :class:`hybridship.physics.model.DynamicModel`,
except where it runs the physics kernels itself: the environment estimator's compiled filter
(:mod:`.environment_kernel`: ``physics.integrate``, ``physics.rhs``, ``physics.thrusters``),
multi-step training's differentiable physics step (:mod:`.multistep`: ``physics.integrate``,
``physics.rhs``) and the Munk coefficient of :mod:`.drift_hull` (``physics.hull``).
"""
