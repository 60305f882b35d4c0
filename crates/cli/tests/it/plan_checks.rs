//! Independent checks of planned toolpaths (being written).
