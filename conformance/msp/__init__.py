"""Conformance of MSP flight controllers: the MSP.* clauses (role msp, issue 25).

`mavconform run --target builtin:msp | msp-mutant:NAME | msp:tcp:HOST:PORT | msp:serial:DEV`
judges an MSP waypoint store (INAV's, as the MSP that flies today): clauses.py holds the
clauses with their sources, checks.py one check each, target.py and session.py the link,
tester.py the bounded request/reply client, runner.py the run (the mission put back after),
mutants.py the negative controls, suite.py the run from options to reports.
"""
