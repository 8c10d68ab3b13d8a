"""Navigation among people: security zones (seed 001), Nearness Diagram, the planners behind one interface
(``command(stamp, pose, velocity, obstacles, tracks, goal) -> (v, omega)``) and person following with a tag."""
