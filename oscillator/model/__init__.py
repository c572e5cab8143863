"""The article's system: parameters, phase space, vector fields, G-functions, the switching theorems
5.1-5.9, the root functions that watch the boundaries, the switching decisions and the energy.

Pure functions and frozen dataclasses only; nothing here integrates or keeps state.
"""
