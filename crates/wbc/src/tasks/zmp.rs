//! The global ZMP of the contact wrenches equal to `r*` = `input.desired_zmp` [Romualdi 2022,
//! eq. 7.2.23–7.2.24] (TSID): with `z₀` the mean height of the loaded contacts,
//! `Σ_c (p_{c,z} − z₀) f_{c,x} + (r*_x − p_{c,x}) f_{c,z} + μ_{c,y} = 0` and
//! `Σ_c (p_{c,z} − z₀) f_{c,y} + (r*_y − p_{c,y}) f_{c,z} − μ_{c,x} = 0` (2 rows, N m).

use stride_qp::TaskDataMut;

use super::TsidContext;
use crate::io::WbcInput;

/// Fills the 2 ZMP rows over the wrench columns of the loaded contacts.
pub(crate) fn fill_zmp(input: &WbcInput, s: &TsidContext, b: &mut TaskDataMut) {
    let zmp = input.desired_zmp.unwrap_or_default();
    // ground height: mean of the loaded contacts' heights
    let mut z0 = 0.0;
    let mut count: f64 = 0.0;
    for (c, contact) in s.contacts.iter().enumerate() {
        if s.offsets[c].is_some() {
            z0 += contact.pose.translation.vector.z;
            count += 1.0;
        }
    }
    z0 /= count.max(1.0);
    for (c, contact) in s.contacts.iter().enumerate() {
        if let Some(off) = s.offsets[c] {
            let p = contact.pose.translation.vector;
            // x: (p_z − z0) f_x + (r_x − p_x) f_z + τ_y = 0 (summed)
            b.a[(0, off)] = p.z - z0;
            b.a[(0, off + 2)] = zmp.x - p.x;
            b.a[(0, off + 4)] = 1.0;
            // y: (p_z − z0) f_y + (r_y − p_y) f_z − τ_x = 0
            b.a[(1, off + 1)] = p.z - z0;
            b.a[(1, off + 2)] = zmp.y - p.y;
            b.a[(1, off + 3)] = -1.0;
        }
    }
    b.b[0] = 0.0;
    b.b[1] = 0.0;
}
