use mcg_hashgrid::{CellKey, HashTable};
#[inline(never)]
pub fn get_one(t: &HashTable<[f32; 8]>, k: &CellKey) -> f32 { t.get(k).map_or(0.0, |v| v[0]) }
#[inline(never)]
pub fn ins_one(t: &mut HashTable<[f32; 8]>, k: &CellKey) { if let Some((v, _)) = t.entry(k) { v[0] += 1.0; } }
#[inline(never)]
pub fn brown_one(m: &hashbrown::HashMap<u64, [f32; 8]>, k: &u64) -> f32 { m.get(k).map_or(0.0, |v| v[0]) }
fn main() {
    let mut t = HashTable::<[f32; 8]>::new(1024, 8, Default::default()).unwrap();
    let k = CellKey::default();
    ins_one(&mut t, &k);
    let m = hashbrown::HashMap::new();
    println!("{} {}", get_one(&t, std::hint::black_box(&k)), brown_one(&m, &3));
}
