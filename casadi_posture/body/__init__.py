"""The body: a kinematic tree of revolute DOFs, anthropometry, the built-in models, loads."""
