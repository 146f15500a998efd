"""fuzzyfire.synth: procedural flames, 3D environments, Method 1 and Method 2 synthetic images."""
