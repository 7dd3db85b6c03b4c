"""Part 105 as data and as files: the only package that knows the standard's entities and its
two layouts (the 1996 edition as used by AP214, and AP242's).

``catalogue`` holds the vocabulary as data; the other modules read and write the layouts.
Imports flow one way: ``part105 -> schema -> step`` and ``part105 -> kinematics``; never
``part105 -> rules, cli, corpus``.
"""
