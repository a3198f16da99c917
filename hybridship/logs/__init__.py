"""Vessel logs: the project log format (read, write, validate) and conversion to arrays."""
