"""The files users give and get that are not models, one reader or writer each.

* :mod:`.values`: driven pair values (``solve --values/--set/--sweep``) into driven columns;
* :mod:`.poses`: pose files ``{t, pose}`` JSON Lines / ``t,m00..m23`` CSV (``solve --path``,
  ``solve --keypoints``);
* :mod:`.solve_records`: solve's JSON Lines / CSV records and summary;
* :mod:`.samples`: interpolate's JSON Lines / CSV;
* :mod:`.graph`: graph's json / dot / graphml / mermaid;
* :mod:`.dh_table`: Denavit-Hartenberg tables, CSV and JSON.

No click here: errors are exceptions whose messages name ``FILE:LINE:COL``; the
CLI turns them into exit 2. Models (Part 21, p105/1 JSON) are read by
:mod:`p105cli.step` and interpreted by :mod:`p105cli.part105`.
"""
