"""The simulated rig and sessions with known truth: points, rendered images, emulated devices, faults, truth files."""
