//! Agreement with OpenCAMLib (reference CSVs committed under fixtures/ocl/).
