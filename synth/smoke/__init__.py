"""Smoke, the second fuzzy object: simulated plumes, soft-alpha mattes of a user's labelled smoke, and where a plume
goes in a Method 2 image."""
