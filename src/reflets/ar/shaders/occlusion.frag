// Provides the self-occlusion pass's fragment stage: the point's value, summed over batches by additive blending.
flat in float v_value;

layout(location = 0) out float out_value;

void main() {
    out_value = v_value;
}
