"""The accuracy study's plug-in (cases/accuracy/study.toml; docs/studies.md, Writing a plug-in):
the table of how far apart the schemes are at their smallest Δt, per mesh
(report_generic.scheme_limits_section), which no data kind draws."""

import report_generic as RG
from report_page import Section


def scheme_limits(ctx, section):
    return [RG.scheme_limits_section({"out": ctx.out}, ctx.sweep(section["sweep"]), Section,
                                     sid="scheme_limits")]
