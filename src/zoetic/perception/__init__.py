"""Animat vision: eyes that image the rendered world (``eyes``), colour recognition
(``recognition``), gaze control (``gaze``) and vision-guided pursuit (``pursuit``)."""
