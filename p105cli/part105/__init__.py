"""Part 105 as data and as files: the only package that knows the standard's entities and its
two layouts (the 1996 edition as used by AP214, and AP242's).

* ``catalogue``: the vocabulary as data (profiles, kinematic entities, pair entities and kinds,
  higher-pair geometry attributes, ranges and limits);
* ``model_file``: ``ModelFile``, a file read once (profile chosen once, population built once)
  with checked access naming ``#id`` and attribute, and a lenient mode for the validator;
* ``layout``: both layouts walked once, and THE names of links and pairs;
* ``pair_values``: ``*_pair_value`` instances in SI, one reader per pair-value family;
* ``read_mechanism``: a ModelFile as ``kinematics.model.Mechanism`` objects;
* ``motion``: paths and configuration sequences of a model file;
* ``geometry``: Part 42 instances <-> ``kinematics.geometry`` objects;
* ``topology``: the ``graph --enrich`` entities;
* ``builder``: records with id allocation, for the writers.

Imports flow one way: ``part105 -> schema -> step`` and ``part105 -> kinematics``; never
``part105 -> rules, cli, corpus``.
"""
