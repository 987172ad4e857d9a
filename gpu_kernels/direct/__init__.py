"""Direct light: geometry upload, shadow maps, the G-buffer and the Diffuse Direct pass."""
