"""Conformance of ground stations and SDKs: the suite plays the vehicle.

`mavconform run --role gcs` judges the GCS side of the Mission Protocol (the MIS.G.*
clauses, clauses.py): a scripted vehicle (scripted_vehicle.py) answers as seed 000 says
except where a check's script makes it drop, repeat, mistype, refuse or answer another GCS, and an adapter
(adapters.py) tells the GCS under test to upload, download, clear or set current, once
per operation. checks/ decides each clause from what both sides did; mutants.py (with
mutants_current.py and mutants_routing.py) holds the reference GCS with one behaviour broken
per clause, the negative controls.
"""
