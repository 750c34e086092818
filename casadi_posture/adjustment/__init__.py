"""The fatigue-driven adjustment: reduced active torque algorithm, fatigue constraint."""
