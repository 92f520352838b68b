// Accumulate: one I*S term into the frame memory word.
// part = round(w * i / 2^SHIFT) (SHIFT < 0: shift left), acc_out = acc_in + part with the
// frame's overflow mode; ovf flags an overflow. All operands are unsigned.
// QUANT: 0 truncate (TRN, TRN_ZERO), 1 ties up (RND, RND_INF), 2 ties down
// (RND_ZERO, RND_MIN_INF), 3 ties to even (RND_CONV).
// OVF: 0 wrap, 1 saturate to the maximum (SAT, SAT_SYM, ERROR), 2 saturate to zero.
// Timing: combinational multiply/round/add, output registered (latency 1, one term per clock).
module acc_mac #(
    parameter W_BITS = 10,
    parameter I_BITS = 16,
    parameter F_BITS = 12,
    parameter SHIFT  = 14,
    parameter QUANT  = 3,
    parameter OVF    = 1
) (
    input  wire              clk,
    input  wire [W_BITS-1:0] w,
    input  wire [I_BITS-1:0] i,
    input  wire [F_BITS-1:0] acc_in,
    output reg  [F_BITS-1:0] acc_out,
    output reg               ovf
);
    localparam P_BITS = W_BITS + I_BITS;
    localparam LSH    = (SHIFT < 0) ? -SHIFT : 0;
    localparam S_BITS = P_BITS + LSH + F_BITS + 1;
    wire [P_BITS-1:0] p = w * i;
    wire [S_BITS-1:0] part;
    generate
        if (SHIFT > 0) begin : g_round
            wire [P_BITS-1:0] one  = {{(P_BITS-1){1'b0}}, 1'b1};
            wire [P_BITS-1:0] half = one << (SHIFT - 1);
            wire [P_BITS-1:0] rem  = p & ((half << 1) - one);
            wire [P_BITS-1:0] fl   = p >> SHIFT;
            wire up = (QUANT == 0) ? 1'b0 :
                      (QUANT == 1) ? (rem >= half) :
                      (QUANT == 2) ? (rem > half) :
                      ((rem > half) || ((rem == half) && fl[0]));
            assign part = fl + up;
        end else begin : g_shl
            assign part = {{(S_BITS-P_BITS){1'b0}}, p} << LSH;
        end
    endgenerate
    wire [S_BITS-1:0] sum  = part + acc_in;
    wire [S_BITS-1:0] max  = {{(S_BITS-F_BITS){1'b0}}, {F_BITS{1'b1}}};
    wire              over = sum > max;
    always @(posedge clk) begin
        ovf     <= over;
        acc_out <= !over ? sum[F_BITS-1:0] :
                   (OVF == 0) ? sum[F_BITS-1:0] :
                   (OVF == 1) ? {F_BITS{1'b1}} : {F_BITS{1'b0}};
    end
endmodule
