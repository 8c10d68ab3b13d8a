"""People perception: data types, laser detection, fusion and tracking (the SPENCER framework's equivalent)."""
