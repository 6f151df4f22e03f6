//! `vcm.read`, `vcm.write`, `vcm.compare` and the conversions between images and numpy arrays
//! (float32, `(height, width, 3)`, top row first, linear sRGB).

use std::path::PathBuf;

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::value_error;

/// Hands `pixels` (row-major, top row first) to numpy as a float32 `(height, width, 3)` array:
/// the buffer moves into the array, no copy.
pub fn pixels_to_array(py: Python<'_>, pixels: Vec<[f32; 3]>, width: u32, height: u32) -> PyResult<Bound<'_, PyAny>> {
    let flat = PyArray1::from_vec(py, pixels.into_flattened());
    Ok(flat.reshape([height as usize, width as usize, 3])?.into_any())
}

/// An image from a numpy array (or anything `numpy.asarray` takes) of shape `(height, width,
/// 3)`; converted to float32 when needed. `name` names the argument in errors.
fn array_to_image(py: Python<'_>, array: &Bound<'_, PyAny>, name: &str) -> PyResult<io::Image> {
    let numpy = py.import("numpy")?;
    let converted = numpy.call_method1("ascontiguousarray", (array, numpy.getattr("float32")?))?;
    let array: PyReadonlyArrayDyn<'_, f32> = converted.extract()?;
    let shape = array.shape().to_vec();
    let [height, width, 3] = shape[..] else {
        return Err(PyValueError::new_err(format!(
            "{name}: expected an array of shape (height, width, 3), got {shape:?}"
        )));
    };
    if width == 0 || height == 0 {
        return Err(PyValueError::new_err(format!("{name}: the image is empty ({shape:?})")));
    }
    let values = array.as_slice().map_err(|e| PyValueError::new_err(format!("{name}: {e}")))?;
    let pixels = values.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    Ok(io::Image { width, height, pixels })
}

/// An image from a path (read by extension) or an array.
fn image_argument(py: Python<'_>, value: &Bound<'_, PyAny>, name: &str) -> PyResult<io::Image> {
    match value.extract::<PathBuf>() {
        Ok(path) => read_image(&path),
        Err(_) => array_to_image(py, value, name),
    }
}

fn read_image(path: &std::path::Path) -> PyResult<io::Image> {
    io::read_image(path).map_err(|e| PyOSError::new_err(format!("cannot read '{}': {e}", path.display())))
}

/// Reads an image file (EXR, PFM, HDR or PNG, by extension) into a float32 `(height, width, 3)`
/// array, linear sRGB (PNG is decoded from sRGB), top row first.
#[pyfunction]
pub fn read(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let image = read_image(&path)?;
    let (width, height) = (image.width as u32, image.height as u32);
    pixels_to_array(py, image.pixels, width, height)
}

/// Writes a `(height, width, 3)` array (linear sRGB, top row first) to an image file whose
/// format follows the extension: EXR, PFM, HDR (linear) or PNG (sRGB-encoded, clamped; the
/// exposure in stops scales PNG only).
#[pyfunction]
#[pyo3(signature = (path, array, exposure = 0.0))]
pub fn write(py: Python<'_>, path: PathBuf, array: &Bound<'_, PyAny>, exposure: f32) -> PyResult<()> {
    let image = array_to_image(py, array, "array")?;
    let options = io::WriteOptions { exposure_stops: exposure };
    py.detach(|| io::write_image(&path, &image, &options))
        .map_err(|e| PyOSError::new_err(format!("cannot write '{}': {e}", path.display())))
}

/// Compares a test image `a` with a reference `b` (arrays or image files), as `vcm compare`:
/// a dict with `pixels` (compared), `non_finite` (excluded pixels), `rmse`, `relmse` (mean of
/// (a-b)^2 / (b^2 + 0.01)), `mae`, `means_a`, `means_b` (per channel) and `z_test`: `None`, or
/// with both variances (of the means, e.g. `Session.variance()`) the per-pixel Z-test at
/// family-wise level `alpha` (Šidák): a dict with `passed`, `failing`, `entries`, `worst_z`,
/// `worst_pixel` (x, y), `worst_channel`, `threshold_p`.
#[pyfunction]
#[pyo3(signature = (a, b, variance_a = None, variance_b = None, alpha = 1e-3))]
pub fn compare<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    variance_a: Option<&Bound<'py, PyAny>>,
    variance_b: Option<&Bound<'py, PyAny>>,
    alpha: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let a = image_argument(py, a, "a")?;
    let b = image_argument(py, b, "b")?;
    let variances = match (variance_a, variance_b) {
        (Some(va), Some(vb)) => Some((image_argument(py, va, "variance_a")?, image_argument(py, vb, "variance_b")?)),
        (None, None) => None,
        _ => return Err(PyValueError::new_err("the Z-test needs both variance_a and variance_b")),
    };
    let variance = variances.as_ref().map(|(va, vb)| (va, vb));
    let m = image_metrics::metrics(&a, &b, variance, alpha).map_err(value_error)?;
    let result = PyDict::new(py);
    result.set_item("pixels", m.pixels)?;
    result.set_item("non_finite", m.non_finite)?;
    result.set_item("rmse", m.rmse)?;
    result.set_item("relmse", m.relative_mse)?;
    result.set_item("mae", m.mean_absolute_error)?;
    result.set_item("means_a", m.means_a.to_vec())?;
    result.set_item("means_b", m.means_b.to_vec())?;
    match m.z_test {
        Some(z) => {
            let test = PyDict::new(py);
            test.set_item("passed", z.passed)?;
            test.set_item("failing", z.failing)?;
            test.set_item("entries", z.entries)?;
            test.set_item("worst_z", z.worst_z)?;
            test.set_item("worst_pixel", z.worst_pixel)?;
            test.set_item("worst_channel", z.worst_channel)?;
            test.set_item("threshold_p", z.threshold_p)?;
            result.set_item("z_test", test)?;
        }
        None => result.set_item("z_test", py.None())?,
    }
    Ok(result)
}
