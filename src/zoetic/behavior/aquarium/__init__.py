"""The aquarium: fish species, the perception oracle, behaviour routines and a tank to live in."""
