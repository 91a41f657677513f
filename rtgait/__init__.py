"""rtgait: real-time humanoid gait planning by the analytical method of Harada, Kajita, Kaneko and Hirukawa."""

__version__ = "0.1.0"
