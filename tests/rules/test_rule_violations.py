"""One violation per WHERE/UNIQUE rule of the Part 105 kinematics entities.

For every (profile, rule id) in ``MUTATIONS`` a small, readable text edit of
a generated corpus file (``tests/data/corpus/<mechanism>_<profile>.stp``)
breaks exactly that rule; the unmodified corpus file is the passing twin
(it has no diagnostics at all). Each case asserts that

* the rule is reported, with severity ``error``, on the expected instance;
* the set of rule ids reported for the mutated file is exactly the expected
  one: the rule itself, plus (only where breaking it necessarily breaks
  something else) the listed companions, each explained in ``why``.

``test_rule_coverage_is_complete`` computes the kinematics-entity WHERE and
UNIQUE rules that apply to the corpus per profile and fails when one is
neither in ``MUTATIONS`` nor in ``NOT_COVERED`` (with its reason), or when
``NOT_COVERED`` lists a rule that is covered or does not apply.

Part 21 edits are functions on the text (one instance per line,
``#id=TYPE(args);``): ``sub`` replaces a fragment inside one instance,
``add`` appends a new instance (ids from 9001 on, readable and clear of the
corpus ids), ``chain`` composes edits.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Callable

import pytest

from p105cli.rules.validate import (
    Validation,
    _evaluate_rules,
    kinematic_entity_names,
    validate_document,
)
from p105cli.schema.population import Population
from p105cli.schema.profiles import profile_for_header
from p105cli.step import read_step

CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"
PROFILES = ("ap214", "ap242", "p105")
SCHEMA_ARG = {"ap214": None, "ap242": None, "p105": "p105"}


# ---------------------------------------------------------------- text edits

Edit = Callable[[str], str]


def _line_span(text: str, iid: int) -> tuple[int, int]:
    m = re.search(rf"^#{iid}=.*?;[ \t]*$", text, flags=re.M)
    assert m, f"#{iid} not found"
    return m.start(), m.end()


def sub(iid: int, old: str, new: str) -> Edit:
    """Replace the fragment ``old`` (exactly once) inside the instance line ``#iid``."""

    def edit(text: str) -> str:
        start, end = _line_span(text, iid)
        line = text[start:end]
        body = line[len(f"#{iid}="):]
        assert body.count(old) == 1, f"{old!r} occurs {body.count(old)} times in {line!r}"
        return text[:start] + f"#{iid}=" + body.replace(old, new) + text[end:]

    edit.__doc__ = f"#{iid}: {old} -> {new}"
    return edit


def add(iid: int, body: str) -> Edit:
    """Append the instance ``#iid=body;`` at the end of the DATA section."""

    def edit(text: str) -> str:
        assert not re.search(rf"^#{iid}=", text, flags=re.M), f"#{iid} already used"
        k = text.rindex("\nENDSEC;")
        return text[:k] + f"\n#{iid}={body};" + text[k:]

    edit.__doc__ = f"+ #{iid}={body}"
    return edit


def chain(*edits: Edit) -> Edit:
    def edit(text: str) -> str:
        for e in edits:
            text = e(text)
        return text

    edit.__doc__ = "; ".join(e.__doc__ or "" for e in edits)
    return edit


# ---------------------------------------------------------------- corpus cache

@lru_cache(maxsize=None)
def base_text(mechanism: str, profile: str) -> str:
    return (CORPUS / f"{mechanism}_{profile}.stp").read_text()


def validate_text(text: str, profile: str, name: str = "x.stp"):
    return validate_document(read_step(text, name), name, schema=SCHEMA_ARG[profile])


@lru_cache(maxsize=None)
def base_result(mechanism: str, profile: str):
    return validate_text(base_text(mechanism, profile), profile, f"{mechanism}_{profile}.stp")


@lru_cache(maxsize=None)
def applicable_kinematic_rules(profile: str) -> frozenset:
    """(profile, rule id) of the kinematics entities' WHERE/UNIQUE rules the corpus exercises."""
    kin = kinematic_entity_names()
    out = set()
    for path in sorted(CORPUS.glob(f"*_{profile}.stp")):
        doc = read_step(path.read_text(), path.name)
        prof = profile_for_header(doc.header, SCHEMA_ARG[profile])
        pop = Population(doc, prof)
        v = Validation(path.name, doc)
        _evaluate_rules(pop, prof, v)
        for rule in v.applicable:
            entity = rule[len("SCH-"):].split(".")[0]
            if entity in kin and entity in prof.schema.entities:
                out.add((profile, rule))
    return frozenset(out)


# ---------------------------------------------------------------- the table

@dataclass(frozen=True)
class Mutation:
    profile: str
    rule: str  # SCH-<entity>.<label>
    mechanism: str
    edit: Edit
    entity: int  # the instance the rule is reported on
    also: frozenset = field(default_factory=frozenset)  # other rule ids that necessarily fire
    why: str = ""  # why ``also`` is not empty

    @property
    def id(self) -> str:
        return f"{self.profile}:{self.rule[4:]}"


def M(profile, rule, mechanism, edit, entity, also=(), why=""):
    assert not also or why, f"{rule}: say why {also} fire too"
    return Mutation(profile, f"SCH-{rule}", mechanism, edit, entity, frozenset(also), why)


RANGE_WHY = ("every pair has a value in each written state and no value lies in a range whose "
             "lower limit is not below its upper one: KIN-RANGE reports those values")

MUTATIONS: list[Mutation] = [
    # ============================================================ ap214 (Part 105:1996 layout)
    M("ap214", "gear_pair_range.wr1", "gear_train",
      sub(225, "PLANE_ANGLE_MEASURE(-3600.)", "PLANE_ANGLE_MEASURE(3600.)"), 225, also={"KIN-RANGE"}, why=RANGE_WHY),
    M("ap214", "initial_state.wr1", "cam_follower",
      sub(177, "(#173,#174,#176)", "(#173,#174)"), 177),
    M("ap214", "kinematic_frame_background_representation.wr1", "cam_follower",
      # a second background, planar: 2D items in a 2D context (a 3D item there breaks compatible_dimension)
      chain(add(9001, "GEOMETRIC_REPRESENTATION_CONTEXT('2d','2D',2)"),
            add(9002, "CARTESIAN_POINT('',(0.,0.))"),
            add(9003, "AXIS2_PLACEMENT_2D('',#9002,$)"),
            add(9004, "CIRCLE('planar profile',#9003,40.)"),
            add(9005, "KINEMATIC_FRAME_BACKGROUND_REPRESENTATION('planar background',(#9004),#9001)")), 9005),
    M("ap214", "kinematic_frame_background_representation_association.wr1", "cam_follower",
      # rep_1: a plain representation that still holds the transformator (#132)
      chain(add(9001, "REPRESENTATION('not a link',(#132),#9)"), sub(197, "#144,", "#9001,")), 197),
    M("ap214", "kinematic_frame_background_representation_association.wr2", "cam_follower",
      # rep_2: a plain representation with the background's items
      # (a second association: the one the contact pair needs, #197, stays intact)
      chain(add(9001, "REPRESENTATION('not a background',(#156,#170,#175,#181,#186),#193)"),
            add(9002, "KINEMATIC_FRAME_BACKGROUND_REPRESENTATION_ASSOCIATION('second',$,#144,#9001,#195)")),
      9002),
    M("ap214", "kinematic_frame_background_representation_association.wr3", "cam_follower",
      # a second association whose transformator is the follower's contact frame, not an item of the cam's
      chain(add(9001, "KINEMATIC_FRAME_BASED_TRANSFORMATION('other','other',$,#136)"),
            add(9002, "REPRESENTATION('other placement',(#9001),#9)"),
            add(9003, "KINEMATIC_FRAME_BACKGROUND_REPRESENTATION_ASSOCIATION('second',$,#144,#194,#9001)")),
      9003),
    M("ap214", "kinematic_frame_based_transformation.wr1", "cam_follower",
      # dim of the transformation comes from the context of the representation using it
      chain(add(9001, "GEOMETRIC_REPRESENTATION_CONTEXT('2d','2D',2)"),
            sub(196, "#9)", "#9001)")), 195,
      also={"SCH-compatible_dimension.wr1", "SCH-compatible_dimension.wr2"},
      why="dim is that of the using representation's context; the transformator is an axis2_placement_3d "
          "(rigid_placement), so its point (wr1) and directions (wr2) end up in a 2D context"),
    M("ap214", "kinematic_ground_representation.wr1", "cam_follower",
      # a second ground representation, of a non-geometric item (geometric items there break
      # geometric_representation_item.wr1)
      chain(add(9001, "REPRESENTATION_CONTEXT('not geometric','3D')"),
            add(9002, "DESCRIPTIVE_REPRESENTATION_ITEM('note','ground')"),
            add(9003, "KINEMATIC_GROUND_REPRESENTATION('ground 2',(#9002),#9001)")), 9003),
    M("ap214", "kinematic_joint.wr1", "four_bar",
      # joint A joins the crank to itself; pair A's first frame moves onto the crank (kinematic_pair.wr1)
      chain(sub(135, "(#131,#132)", "(#132,#132)"), sub(188, "#143,#147,#135)", "#151,#147,#135)")), 135),
    M("ap214", "kinematic_link.wr1", "cam_follower",
      add(9001, "KINEMATIC_LINK()"), 9001,
      also={"SCH-kinematic_link.wr2", "KIN-UNREACHABLE"},
      why="a link in no joint has no structure, so unique_link_usage (wr2) is FALSE, and no mechanism "
          "reaches it (KIN-UNREACHABLE warning)"),
    M("ap214", "kinematic_link.wr2", "cam_follower",
      # a second structure (of no mechanism) uses a joint of the follower
      chain(add(9001, "KINEMATIC_JOINT(#106,#108)"), add(9002, "KINEMATIC_STRUCTURE((#9001))")), 108),
    M("ap214", "kinematic_link_representation.wr1", "cam_follower",
      sub(141, "(#116,#124)", "(#116,#124,#113)"), 141),
    M("ap214", "kinematic_link_representation_association.wr1", "cam_follower",
      # rep_2: the assembly shape (world context #7), rep_1 is in the frame link context #8
      sub(143, "#141,#28)", "#141,#85)"), 143),
    M("ap214", "kinematic_link_representation_association.wr2", "cam_follower",
      sub(143, "#141,#28)", "#141,#141)"), 143),
    M("ap214", "kinematic_link_representation_relation.ur1", "cam_follower",
      add(9001, "KINEMATIC_LINK_REPRESENTATION_RELATION(#106,#144)"), 9001),
    M("ap214", "kinematic_pair.ur1", "cam_follower",
      add(9001, "REVOLUTE_PAIR('shaft 2','second pair on the shaft joint',#116,#120,#109)"), 9001),
    M("ap214", "kinematic_pair.wr1", "cam_follower",
      sub(150, "#116,#120,#109)", "#120,#120,#109)"), 150),
    M("ap214", "kinematic_pair.wr2", "cam_follower",
      sub(150, "#116,#120,#109)", "#116,#128,#109)"), 150),
    M("ap214", "kinematic_property_representation_relation.ur1", "cam_follower",
      add(9001, "KINEMATIC_PROPERTY_REPRESENTATION_RELATION(#164,#163)"), 9001),
    M("ap214", "kinematic_property_representation_relation.wr1", "cam_follower",
      add(9001, "KINEMATIC_PROPERTY_REPRESENTATION_RELATION(#27,#163)"), 9001),
    M("ap214", "kinematic_property_representation_relation.wr2", "cam_follower",
      chain(add(9001, "KINEMATIC_PROPERTY_DEFINITION('other','',#83,#26)"),
            add(9002, "KINEMATIC_PROPERTY_REPRESENTATION_RELATION(#9001,#141)")), 9002),
    M("ap214", "mechanism.wr1", "cam_follower",
      # a second mechanism of two new links, based on the frame, which none of its joints touches
      chain(add(9001, "KINEMATIC_LINK()"), add(9002, "KINEMATIC_LINK()"),
            add(9003, "KINEMATIC_JOINT(#9001,#9002)"), add(9004, "KINEMATIC_STRUCTURE((#9003))"),
            add(9005, "MECHANISM(#9004,#106,#164)")), 9005),
    M("ap214", "mechanism_base_placement.wr1", "cam_follower",
      chain(add(9001, "REPRESENTATION('ground',(#68,#162),#7)"), sub(167, "$,#163,", "$,#9001,")), 167,
      also={"SCH-NOT-EVALUATED"},
      why="suitably_based_mechanism (wr2) treats any rep_1 that is not a ground representation as a link "
          "representation; for one that is neither, its recursion on indeterminate values never ends, "
          "so wr2 is reported not evaluated (a note)"),
    M("ap214", "mechanism_base_placement.wr2", "cam_follower",
      # the ground representation belongs to another kinematic property
      chain(add(9001, "KINEMATIC_PROPERTY_DEFINITION('other','',#83,#26)"),
            add(9002, "KINEMATIC_PROPERTY_REPRESENTATION_RELATION(#9001,#163)"),
            sub(165, "(#164,#163)", "(#164,#9003)"),
            add(9003, "KINEMATIC_GROUND_REPRESENTATION('ground 2',(#68),#7)")), 167),
    M("ap214", "mechanism_base_placement.wr3", "cam_follower",
      # the operator leaves the ground representation but stays an item of another one
      chain(sub(163, "(#68,#162)", "(#68)"), add(9001, "REPRESENTATION('holder',(#162),#7)")), 167),
    M("ap214", "mechanism_base_placement.ur1", "cam_follower",
      add(9001, "MECHANISM_BASE_PLACEMENT('base placement 2',$,#163,*,#162,#166)"), 9001),
    M("ap214", "motion_link_relationship.wr1", "cam_follower",
      sub(200, "#147,#140)", "#147,#132)"), 200),
    M("ap214", "pair_actuator.ur1", "cam_follower",
      add(9001, "PAIR_ACTUATOR(#150,'second drive')"), 9001),
    M("ap214", "point_on_planar_curve_pair.wr1", "cam_follower",
      # the pair's frame on the cam is not the transformator of the background association
      sub(157, "#132,#136,#111", "#120,#136,#111"), 157),
    M("ap214", "point_on_planar_curve_pair_range.wr1", "cam_follower",
      sub(170, "#156,", "#42,"), 171),
    M("ap214", "point_on_planar_curve_pair_range.wr2", "cam_follower",
      sub(171, "#170,UNLIMITED_RANGE(.UNLIMITED.),UNLIMITED_RANGE(.UNLIMITED.),",
          "#170,PLANE_ANGLE_MEASURE(10.),PLANE_ANGLE_MEASURE(10.),"), 171, also={"KIN-RANGE"}, why=RANGE_WHY),
    M("ap214", "point_on_planar_curve_pair_range.wr3", "cam_follower",
      sub(171, "UNLIMITED_RANGE(.UNLIMITED.),UNLIMITED_RANGE(.UNLIMITED.),UNLIMITED_RANGE(.UNLIMITED.),"
               "UNLIMITED_RANGE(.UNLIMITED.));",
          "PLANE_ANGLE_MEASURE(0.),PLANE_ANGLE_MEASURE(0.),UNLIMITED_RANGE(.UNLIMITED.),"
          "UNLIMITED_RANGE(.UNLIMITED.));"), 171),
    M("ap214", "point_on_planar_curve_pair_range.wr4", "cam_follower",
      sub(171, "UNLIMITED_RANGE(.UNLIMITED.),UNLIMITED_RANGE(.UNLIMITED.));",
          "PLANE_ANGLE_MEASURE(0.),PLANE_ANGLE_MEASURE(0.));"), 171),
    M("ap214", "point_on_planar_curve_pair_value.wr1", "cam_follower",
      sub(175, "#156,", "#42,"), 176),
    M("ap214", "prismatic_pair_range.wr1", "cam_follower",
      sub(169, "LENGTH_MEASURE(23.)", "LENGTH_MEASURE(57.)"), 169, also={"KIN-RANGE"}, why=RANGE_WHY),
    M("ap214", "rack_and_pinion_pair_range.wr1", "rack_and_pinion",
      sub(167, "LENGTH_MEASURE(-120.)", "LENGTH_MEASURE(120.)"), 167, also={"KIN-RANGE"}, why=RANGE_WHY),
    M("ap214", "revolute_pair_range.wr1", "gear_train",
      sub(222, "PLANE_ANGLE_MEASURE(-3600.)", "PLANE_ANGLE_MEASURE(3600.)"), 222, also={"KIN-RANGE"}, why=RANGE_WHY),

    # ============================================================ ap242 (Part 105 ed2 layout)
    M("ap242", "gear_pair.wr1", "gear_train",
      # the mesh's first link representation becomes a (linear flexible) copy of gear_1's
      chain(add(9001, "LINEAR_FLEXIBLE_LINK_REPRESENTATION('gear_1',(#156,#176),#10,#140)"),
            sub(209, "#195,#197,#204)", "#9001,#197,#204)")), 204),
    M("ap242", "gear_pair_with_range.wr1", "gear_train",
      sub(204, "-3600.,3600.)", "3600.,3600.)"), 204, also={"KIN-RANGE"}, why=RANGE_WHY),
    M("ap242", "high_order_kinematic_pair.wr1", "cam_follower",
      chain(add(9001, "LINEAR_FLEXIBLE_LINK_REPRESENTATION('follower',(#126,#134,#138),#11,#106)"),
            sub(151, "#142,#144,#148)", "#142,#9001,#148)")), 148),
    M("ap242", "interpolated_configuration_sequence.wr1", "cam_follower",
      # the last state configures a second mechanism representation (same pairs)
      chain(add(9001, "MECHANISM_REPRESENTATION('cam_follower copy',(#149,#150,#151),#8,#110)"),
            sub(186, "*,#152)", "*,#9001)")), 191),
    M("ap242", "kinematic_joint.wr1", "cam_follower",
      # a new joint (its own topology, so it is used in a representation) from the follower to itself
      chain(add(9001, "KINEMATIC_JOINT('self',#106,#106)"),
            add(9002, "KINEMATIC_TOPOLOGY_STRUCTURE('spare topology',(#9001),#8)")), 9001),
    M("ap242", "kinematic_joint.ur1", "cam_follower",
      chain(add(9001, "KINEMATIC_JOINT('shaft again',#104,#105)"),
            add(9002, "KINEMATIC_TOPOLOGY_STRUCTURE('spare topology',(#9001),#8)")), 9001),
    M("ap242", "kinematic_link_representation_association.wr1", "cam_follower",
      sub(141, "#140,#29)", "#140,#86)"), 141),
    M("ap242", "kinematic_path.wr1", "cam_follower",
      # the path is also an item of a representation whose context has no parameter
      add(9001, "REPRESENTATION('path without parameter',(#207),#8)"), 207),
    M("ap242", "kinematic_property_mechanism_representation.wr1", "cam_follower",
      # base: a rigid representation of the frame that no pair relationship uses
      chain(add(9001, "RIGID_LINK_REPRESENTATION('frame 2',(#114,#122),#9,#104)"),
            sub(154, "#152,#140)", "#152,#9001)")), 154),
    M("ap242", "kinematic_topology_network_structure.wr1", "cam_follower",
      sub(165, "(#164),#8,", "(#164),#9,"), 165),
    M("ap242", "kinematic_topology_network_structure.wr2", "cam_follower",
      # parent: a topology with only two of the loop's three joints
      chain(add(9001, "KINEMATIC_TOPOLOGY_STRUCTURE('partial topology',(#107,#108),#8)"),
            sub(165, "#8,#110)", "#8,#9001)")), 165),
    M("ap242", "kinematic_topology_structure.wr1", "cam_follower",
      # a joint that is also an oriented edge (the shaft joint reversed: its links are derived, so it
      # duplicates no joint), in a topology of its own
      chain(add(9001, "(EDGE(*,*)KINEMATIC_JOINT()ORIENTED_EDGE(#107,.F.)REPRESENTATION_ITEM('reversed shaft')"
                      "TOPOLOGICAL_REPRESENTATION_ITEM())"),
            add(9002, "KINEMATIC_TOPOLOGY_STRUCTURE('odd topology',(#9001),#8)")), 9002),
    M("ap242", "link_motion_relationship.wr1", "cam_follower",
      # item_1: a copy of the tip frame that the follower's representation uses only through a new
      # circle (so representation_relationship_with_transformation.wr2, by using_representations, holds)
      chain(add(9001, "AXIS2_PLACEMENT_3D('tip copy',#135,#136,#137)"),
            add(9002, "CIRCLE('tip circle',#9001,1.)"),
            sub(144, "(#126,#134,#138)", "(#126,#134,#138,#9002)"),
            sub(209, "$,#138,#207)", "$,#9001,#207)")), 210),
    M("ap242", "link_motion_relationship.wr2", "cam_follower",
      chain(add(9001, "KINEMATIC_PATH_DEFINED_BY_NODES('other path',(#201,#206),0.,#196)"),
            add(9002, "REPRESENTATION('other path holder',(#9001),#187)"),
            sub(209, "$,#138,#207)", "$,#138,#9001)")), 210,
      also={"SCH-representation_relationship_with_transformation.wr2"},
      why="item_2 is a kinematic_path and a prescribed_path's items are paths themselves: item_2 cannot be "
          "used in rep_2 other than as one of its items, which rrwt.wr2 (by using_representations) asks too"),
    M("ap242", "low_order_kinematic_pair.wr1", "four_bar",
      chain(add(9001, "LINEAR_FLEXIBLE_LINK_REPRESENTATION('coupler',(#153,#157,#173),#11,#131)"),
            sub(188, "#178,#180,#184)", "#9001,#180,#184)")), 184),
    M("ap242", "low_order_kinematic_pair.wr2", "four_bar",
      chain(add(9001, "LINEAR_FLEXIBLE_LINK_REPRESENTATION('coupler',(#153,#157,#173),#11,#131)"),
            sub(187, "#176,#178,#183)", "#176,#9001,#183)")), 183),
    M("ap242", "low_order_kinematic_pair_with_motion_coupling.wr1", "rack_and_pinion",
      chain(add(9001, "LINEAR_FLEXIBLE_LINK_REPRESENTATION('pinion',(#120,#136),#10,#107)"),
            sub(152, "#145,#143,#149)", "#145,#9001,#149)")), 149),
    M("ap242", "mechanism_representation.wr1", "cam_follower",
      # the mechanism's topology: a structure of two of its three joints
      chain(add(9001, "KINEMATIC_TOPOLOGY_STRUCTURE('partial topology',(#107,#108),#8)"),
            sub(152, "#8,#110)", "#8,#9001)")), 152),
    M("ap242", "pair_representation_relationship.wr1", "cam_follower",
      # the guide's frame placement becomes a copy that the frame's representation uses only through
      # a new circle (so representation_relationship_with_transformation.wr2 still holds)
      chain(add(9001, "AXIS2_PLACEMENT_3D('guide on frame copy',#119,#120,#121)"),
            add(9002, "CIRCLE('guide circle',#9001,1.)"),
            sub(140, "(#114,#122)", "(#114,#122,#9002)"),
            sub(147, "#122,#126,#108", "#9001,#126,#108")), 150),
    M("ap242", "pair_representation_relationship.wr2", "cam_follower",
      chain(add(9001, "AXIS2_PLACEMENT_3D('guide on follower copy',#123,#124,#125)"),
            add(9002, "CIRCLE('guide circle',#9001,1.)"),
            sub(144, "(#126,#134,#138)", "(#126,#134,#138,#9002)"),
            sub(147, "#122,#126,#108", "#122,#9001,#108")), 150),
    M("ap242", "pair_representation_relationship.wr3", "cam_follower",
      # rep_1 holds the right items but represents the cam, not the joint's start (frame)
      chain(add(9001, "RIGID_LINK_REPRESENTATION('frame as cam',(#114,#122),#9,#105)"),
            sub(150, "#140,#144,#147)", "#9001,#144,#147)")), 150),
    M("ap242", "pair_representation_relationship.wr4", "cam_follower",
      chain(add(9001, "RIGID_LINK_REPRESENTATION('follower as cam',(#126,#134,#138),#11,#105)"),
            sub(150, "#140,#144,#147)", "#140,#9001,#147)")), 150),
    M("ap242", "point_on_planar_curve_pair.wr1", "cam_follower",
      # the cam's representation in the contact relationship lacks the pair curve (#43)
      chain(add(9001, "RIGID_LINK_REPRESENTATION('cam 2',(#118,#130,#139),#10,#105)"),
            sub(151, "#142,#144,#148)", "#9001,#144,#148)")), 148),
    M("ap242", "point_on_planar_curve_pair.wr2", "cam_follower",
      chain(add(9001, "LINEAR_FLEXIBLE_LINK_REPRESENTATION('cam',(#118,#130,#43,#139),#10,#105)"),
            sub(151, "#142,#144,#148)", "#9001,#144,#148)")), 148),
    M("ap242", "point_on_planar_curve_pair_value.wr1", "cam_follower",
      sub(168, "#43,", "#139,"), 171),
    M("ap242", "point_on_planar_curve_pair_with_range.wr1", "cam_follower",
      sub(148, "#139,$,$,$,$,$,$)", "#139,$,$,0.,0.,$,$)"), 148),
    M("ap242", "point_on_planar_curve_pair_with_range.wr2", "cam_follower",
      sub(148, "#139,$,$,$,$,$,$)", "#139,10.,10.,$,$,$,$)"), 148, also={"KIN-RANGE"}, why=RANGE_WHY),
    M("ap242", "point_on_planar_curve_pair_with_range.wr3", "cam_follower",
      sub(148, "#139,$,$,$,$,$,$)", "#139,$,$,$,$,0.,0.)"), 148),
    M("ap242", "point_on_planar_curve_pair_with_range.wr4", "cam_follower",
      chain(add(9001, "TRIMMED_CURVE('same range, another instance',#43,(PARAMETER_VALUE(0.)),(PARAMETER_VALUE(360.)),.T.,"
                      ".PARAMETER.)"),
            sub(148, "#139,$,$,$,$,$,$)", "#9001,$,$,$,$,$,$)")), 148),
    M("ap242", "prismatic_pair_with_range.wr1", "cam_follower",
      sub(147, "23.,57.)", "57.,57.)"), 147, also={"KIN-RANGE"}, why=RANGE_WHY),
    M("ap242", "product_definition_kinematics.ur1", "cam_follower",
      add(9001, "PRODUCT_DEFINITION_KINEMATICS('kinematics 2','',#84)"), 9001),
    M("ap242", "product_definition_relationship_kinematics.ur1", "cam_follower",
      add(9001, "PRODUCT_DEFINITION_RELATIONSHIP_KINEMATICS('frame 2','',#88)"), 9001),
    M("ap242", "rack_and_pinion_pair.wr1", "rack_and_pinion",
      chain(add(9001, "LINEAR_FLEXIBLE_LINK_REPRESENTATION('rack',(#128,#132,#140),#11,#108)"),
            sub(152, "#145,#143,#149)", "#9001,#143,#149)")), 149),
    M("ap242", "rack_and_pinion_pair_with_range.wr1", "rack_and_pinion",
      sub(149, "25.,-120.,120.)", "25.,120.,120.)"), 149, also={"KIN-RANGE"}, why=RANGE_WHY),
    M("ap242", "revolute_pair_with_range.wr1", "four_bar",
      sub(184, "20.,64.)", "64.,64.)"), 184, also={"KIN-RANGE"}, why=RANGE_WHY),
    M("ap242", "rotation_about_direction.wr1", "cam_follower",
      sub(169, "(0.,0.,1.)", "(0.,1.)"), 170,
      also={"SCH-compatible_dimension.wr1"},
      why="the direction is in the 3D context of the mechanism state, and a direction's dimension must "
          "match its context's (compatible_dimension, one WHERE rule in AP242)"),
    M("ap242", "su_parameters.wr1", "ur5_arm",
      # the base link's representation (only su_parameters in it) gets a 2D context, with units
      chain(add(9001, "(GEOMETRIC_REPRESENTATION_CONTEXT(2)GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#7))"
                      "GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#5,#6))REPRESENTATION_CONTEXT('ur5_arm link base 2d','2D'))"),
            sub(229, "#9,#199)", "#9001,#199)")), 213,
      also={"SCH-kinematic_link_representation_association.wr1"},
      why="su_parameters are only items of link representations, whose context must be that of the "
          "associated shape representation (3D: its points would break compatible_dimension in 2D)"),
]

# The p105 profile (validated with schema="p105") has the 1996 layout of ap214; its corpus files are the
# ap214 ones byte for byte below the header (ur5_arm aside), so every ap214 mutation is replayed on them.
MUTATIONS += [Mutation("p105", m.rule, m.mechanism, m.edit, m.entity, m.also, m.why)
              for m in MUTATIONS if m.profile == "ap214"]
MUTATIONS.append(
    M("p105", "su_parameters.wr1", "ur5_arm",
      # the base link's representation (only su_parameters in it) gets a 2D context, with units
      chain(add(9001, "(GEOMETRIC_REPRESENTATION_CONTEXT(2)GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#6))"
                      "GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#4,#5))REPRESENTATION_CONTEXT('ur5_arm link base 2d','2D'))"),
            sub(231, "(#215),#8)", "(#215),#9001)")), 215,
      also={"SCH-kinematic_link_representation_association.wr1"},
      why="su_parameters are only items of link representations, whose context must be that of the "
          "associated shape representation (3D: its points would break compatible_dimension in 2D)"))

# Kinematics-entity rules that apply to the corpus but have no mutation, with the reason.
NOT_COVERED: dict[tuple[str, str], str] = {
}


# ---------------------------------------------------------------- the tests

def _rules(result) -> set:
    return {d.rule for d in result.diagnostics}


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("mechanism", sorted({m.mechanism for m in MUTATIONS}))
def test_passing_twin_is_clean(mechanism, profile):
    result = base_result(mechanism, profile)
    assert [(d.rule, d.entity) for d in result.diagnostics] == []


@pytest.mark.parametrize("m", MUTATIONS, ids=lambda m: m.id)
def test_mutation_violates_exactly_its_rule(m: Mutation):
    assert not base_result(m.mechanism, m.profile).diagnostics
    text = m.edit(base_text(m.mechanism, m.profile))
    result = validate_text(text, m.profile)
    hits = [d for d in result.diagnostics if d.rule == m.rule]
    assert hits, f"{m.rule} not reported; got {sorted(_rules(result))}"
    assert m.entity in {d.entity for d in hits}, \
        f"{m.rule} reported on {[d.entity for d in hits]}, expected #{m.entity}"
    assert all(d.severity == "error" for d in hits)
    assert _rules(result) == {m.rule} | m.also, \
        "\n".join(f"{d.severity}[{d.rule}] #{d.entity}: {d.message[:160]}" for d in result.diagnostics)


def test_mutation_table_is_well_formed():
    keys = [(m.profile, m.rule) for m in MUTATIONS]
    assert len(keys) == len(set(keys)), "a rule is listed twice"
    for m in MUTATIONS:
        assert m.rule not in m.also


def test_rule_coverage_is_complete():
    applicable = set()
    for profile in PROFILES:
        applicable |= applicable_kinematic_rules(profile)
    covered = {(m.profile, m.rule) for m in MUTATIONS}
    missing = applicable - covered - set(NOT_COVERED)
    for profile in PROFILES:
        n_app = sum(1 for p, _ in applicable if p == profile)
        n_cov = sum(1 for p, _ in covered & applicable if p == profile)
        print(f"{profile}: {n_cov}/{n_app} kinematics WHERE/UNIQUE rules violated by a mutation; "
              f"not covered: {sorted(r for p, r in NOT_COVERED if p == profile)}")
    assert not missing, f"neither covered nor in NOT_COVERED: {sorted(missing)}"
    assert not (covered - applicable), f"covered but not applicable: {sorted(covered - applicable)}"
    stale = set(NOT_COVERED) - (applicable - covered)
    assert not stale, f"NOT_COVERED lists covered or inapplicable rules: {sorted(stale)}"
    assert all(reason.strip() for reason in NOT_COVERED.values())
