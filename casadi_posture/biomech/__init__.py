"""Joint biomechanics: external, passive and active torques; strength; endurance; fatigue."""
