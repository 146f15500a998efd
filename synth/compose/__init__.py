"""Compositing: flames laid on a scene as light, the camera's effects and auto exposure, the warm
light a flame casts, and which flames a person can see."""
