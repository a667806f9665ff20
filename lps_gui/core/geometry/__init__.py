"""The camera, the boards and targets and their poses: the geometry every model and simulator shares."""
