//! A measured trade table (`bench trade`'s CSV, read by scene budgets): an error naming the
//! file, line and column, or a table.
#![no_main]

use libfuzzer_sys::fuzz_target;
use palpus::trade::TradeTable;

fuzz_target!(|data: &[u8]| {
    let file = std::path::Path::new("fuzz/trade.csv");
    if let Err(e) = TradeTable::parse(data, file) {
        assert!(e.to_string().contains("fuzz/trade.csv"), "{e}");
    }
});
