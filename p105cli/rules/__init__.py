"""Rules of ``p105 validate``: the diagnostics model and its report formats.

This is the science side of the checker: nothing here imports click. The CLI maps
its options onto :mod:`p105cli.rules.diagnostics` (selection, exit codes) and
:mod:`p105cli.rules.report` (the ``-f`` formats, registered in ``FORMATS``).
"""

from .diagnostics import (NOT_EVALUATED, SEVERITIES, Diagnostic, RunResult, Severity, Summary,
                          exit_code, parse_patterns, register_rule, rule_description,
                          rule_selected, select_rules, worst_exit)

__all__ = ["NOT_EVALUATED", "SEVERITIES", "Diagnostic", "RunResult", "Severity", "Summary",
           "exit_code", "parse_patterns", "register_rule", "rule_description", "rule_selected",
           "select_rules", "worst_exit"]
