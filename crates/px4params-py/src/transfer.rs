//! DroneCAN signatures and CAN transfers for Python.

use px4params_core::crc;
use px4params_core::transfer;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList};

/// CRC-64-WE of a normalized DSDL definition text.
#[pyfunction]
pub fn dsdl_signature(normalized: &[u8]) -> u64 {
    crc::dsdl_signature(normalized)
}

/// The data type signature: `dsdl_signature` extended with the nested composite fields'
/// data type signatures, in field order.
#[pyfunction]
pub fn data_type_signature(dsdl_signature: u64, nested: Vec<u64>) -> u64 {
    crc::data_type_signature(dsdl_signature, &nested)
}

/// The seed of a multi-frame transfer's CRC for a data type signature.
#[pyfunction]
pub fn transfer_crc_seed(signature: u64) -> u16 {
    crc::transfer_crc_seed(signature)
}

/// The data bytes (tail byte included) of the CAN frames carrying `payload`.
#[pyfunction]
#[pyo3(signature = (payload, *, signature, transfer_id, canfd = false))]
pub fn can_frames<'py>(
    py: Python<'py>,
    payload: &[u8],
    signature: u64,
    transfer_id: u8,
    canfd: bool,
) -> PyResult<Bound<'py, PyList>> {
    let seed = crc::transfer_crc_seed(signature);
    let frames =
        transfer::frames(payload, seed, transfer_id, canfd).map(|f| PyBytes::new(py, f.as_bytes()));
    PyList::new(py, frames)
}

/// Checks the frames of one transfer; returns its payload and transfer ID.
#[pyfunction]
#[pyo3(signature = (frames, *, signature))]
pub fn reassemble<'py>(
    py: Python<'py>,
    frames: Vec<Vec<u8>>,
    signature: u64,
) -> PyResult<(Bound<'py, PyBytes>, u8)> {
    let refs: Vec<&[u8]> = frames.iter().map(Vec::as_slice).collect();
    // The frames' bytes hold the payload and more.
    let mut payload = vec![0u8; frames.iter().map(Vec::len).sum()];
    let (transfer_id, len) =
        transfer::receive_into(&refs, crc::transfer_crc_seed(signature), &mut payload)
            .map_err(crate::errors::transfer)?;
    Ok((PyBytes::new(py, &payload[..len]), transfer_id))
}
