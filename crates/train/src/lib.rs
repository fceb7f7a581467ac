//! Host-side training of compensation models (filled by the trainer issue).
