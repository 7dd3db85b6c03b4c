"""p105: Unix-style filters for mechanism kinematics exchanged as ISO 10303-105 data."""

__version__ = "0.1.0"
