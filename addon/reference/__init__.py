"""Ground truth from Cycles: references rendered with settings that make comparisons exact, and cached."""
